/* Writing plans and masks as JSON (docs/spec.md sections Plan and Mask). */
#ifndef QRT_CLI_PLAN_JSON_H
#define QRT_CLI_PLAN_JSON_H

#include <stdio.h>

#include "qrtplan/planner.h"

struct stage_times {
    long convert_us, search_us, certify_us, total_us;
};

/* The shortest decimal that reads back as exactly x, into buf (at least
 * EXACT_NUMBER_LEN bytes): a waypoint on a joint limit must not be printed
 * a hair outside it. */
#define EXACT_NUMBER_LEN 40
void format_exact_number(char *buf, double x);

void plan_write_json(FILE *out, const struct qrt_plan *plan,
                     const struct stage_times *t);
void mask_write_json(FILE *out, const struct qrt_mask *mask);

#endif
