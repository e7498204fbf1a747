/* qrtplan setpoints: a plan as a CSV of timed joint set-points, the CiA
 * 402 master's own synchronised trapezoids (qrtcan/profile.h), for users
 * who drive other controllers. */
#ifndef QRT_CLI_SETPOINTS_H
#define QRT_CLI_SETPOINTS_H

#include <stddef.h>
#include <stdio.h>

#include "qrtcan/master.h"

struct setpoint_options {
    double speed_deg_s[3];  /* per joint, as qrtpland's --speed (30) */
    double accel_deg_s2[3]; /* as its --accel (60) */
    double period_s;        /* between rows (0.01) */
    int wrap_alpha;         /* alpha in (-180, 180], not continuous */
    double limit_deg[3][2]; /* the waypoints' limits, as the master's */
};

/* The defaults above, the limits of docs/spec.md section Arm. */
void setpoints_default(struct setpoint_options *o);

/* The waypoints_deg of an "ok" plan (qrtplan plan's JSON) at path ("-":
 * standard input), at most max of them. Returns the count, or -1 with a
 * message in err. */
int setpoints_read_plan(const char *path, double (*wp)[3], int max, char *err,
                        size_t err_len);

/* The CSV: header t_s,alpha_deg,sigma_deg,eta_deg, then a row every
 * period_s from 0 and one at the end (the last waypoint). Segments follow
 * each other without pause (the master's SDO round trips between them are
 * not in it). Alpha continuous from the first waypoint's (as the master
 * keeps its drive position), or wrapped into (-180, 180]. Returns 0, or -1
 * with a message in err (a waypoint outside the limits, bad options). */
int setpoints_write(FILE *out, const double (*wp)[3], int n,
                    const struct setpoint_options *o, char *err,
                    size_t err_len);

#endif
