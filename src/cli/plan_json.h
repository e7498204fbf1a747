/* Writing plans and masks as JSON (docs/spec.md sections Plan and Mask). */
#ifndef QRT_CLI_PLAN_JSON_H
#define QRT_CLI_PLAN_JSON_H

#include <stdio.h>

#include "qrtplan/planner.h"

struct stage_times {
    long convert_us, search_us, certify_us, total_us;
};

void plan_write_json(FILE *out, const struct qrt_plan *plan,
                     const struct stage_times *t);
void mask_write_json(FILE *out, const struct qrt_mask *mask);

#endif
