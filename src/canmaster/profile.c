/* The synchronised trapezoid of a segment: see include/qrtcan/profile.h. */
#include "qrtcan/profile.h"

#include <math.h>
#include <string.h>

#include "qrtcan/frame.h"
#include "qrtplan/joints.h"

/* below this a joint's step is no move */
#define STILL_DEG 1e-9

void qrtcan_segment_step(const double here[QRTCAN_JOINTS],
                         const double to[QRTCAN_JOINTS],
                         double step[QRTCAN_JOINTS])
{
    int j;
    for (j = 0; j < QRTCAN_JOINTS; j++)
        step[j] = j == 0 ? qrt_wrap_deg(to[0] - qrt_wrap_deg(here[0]))
                         : to[j] - here[j];
}

/* The path parameter's speed and acceleration for the step, and each
 * joint's velocity and acceleration (the one definition of the scaling,
 * for qrtcan_segment_profile and qrtcan_segment_drive_profile). Returns
 * whether some joint moves; QRTCAN_E_ARG for bad limits or a non-finite
 * step. */
static int rates(const double max_speed_deg_s[QRTCAN_JOINTS],
                 const double max_accel_deg_s2[QRTCAN_JOINTS],
                 const double step_deg[QRTCAN_JOINTS], double *speed_out,
                 double *accel_out, double vel[QRTCAN_JOINTS],
                 double acc[QRTCAN_JOINTS])
{
    double speed = 1e300, accel = 1e300; /* path parameter per second */
    int j, moves = 0;
    for (j = 0; j < QRTCAN_JOINTS; j++)
        if (!(max_speed_deg_s[j] > 0.0) || !isfinite(max_speed_deg_s[j]) ||
            !(max_accel_deg_s2[j] > 0.0) || !isfinite(max_accel_deg_s2[j]) ||
            !isfinite(step_deg[j]))
            return QRTCAN_E_ARG;
    for (j = 0; j < QRTCAN_JOINTS; j++) {
        if (fabs(step_deg[j]) < STILL_DEG)
            continue;
        moves = 1;
        if (max_speed_deg_s[j] / fabs(step_deg[j]) < speed)
            speed = max_speed_deg_s[j] / fabs(step_deg[j]);
        if (max_accel_deg_s2[j] / fabs(step_deg[j]) < accel)
            accel = max_accel_deg_s2[j] / fabs(step_deg[j]);
    }
    for (j = 0; j < QRTCAN_JOINTS; j++) {
        int still = fabs(step_deg[j]) < STILL_DEG;
        vel[j] = still ? max_speed_deg_s[j] : fabs(step_deg[j]) * speed;
        acc[j] = still ? max_accel_deg_s2[j] : fabs(step_deg[j]) * accel;
    }
    *speed_out = speed;
    *accel_out = accel;
    return moves;
}

int qrtcan_segment_profile(const double max_speed_deg_s[QRTCAN_JOINTS],
                           const double max_accel_deg_s2[QRTCAN_JOINTS],
                           const double step_deg[QRTCAN_JOINTS],
                           struct qrtcan_segment *seg)
{
    double speed, accel;
    int j, moves;
    memset(seg, 0, sizeof *seg);
    moves = rates(max_speed_deg_s, max_accel_deg_s2, step_deg, &speed, &accel,
                  seg->vel_deg_s, seg->accel_deg_s2);
    if (moves < 0)
        return moves;
    for (j = 0; j < QRTCAN_JOINTS; j++)
        seg->step_deg[j] = step_deg[j];
    seg->moves = moves;
    if (!moves)
        return QRTCAN_OK; /* no time at all */
    seg->speed = speed;
    seg->accel = accel;
    if (speed * speed / accel >= 1.0) { /* a triangle: speed not reached */
        seg->ramp_s = sqrt(1.0 / accel);
        seg->peak = accel * seg->ramp_s;
        seg->cruise_s = 0.0;
    } else {
        seg->ramp_s = speed / accel;
        seg->peak = speed;
        seg->cruise_s = (1.0 - speed * speed / accel) / speed;
    }
    seg->duration_s = 2.0 * seg->ramp_s + seg->cruise_s;
    return QRTCAN_OK;
}

double qrtcan_segment_fraction(const struct qrtcan_segment *seg, double t,
                               double *ds)
{
    double s, v, left = seg->duration_s - t;
    if (!seg->moves || t >= seg->duration_s) {
        s = seg->moves || t >= 0.0 ? 1.0 : 0.0;
        v = 0.0;
    } else if (t <= 0.0) {
        s = 0.0;
        v = 0.0;
    } else if (t < seg->ramp_s) {
        s = 0.5 * seg->accel * t * t;
        v = seg->accel * t;
    } else if (t < seg->ramp_s + seg->cruise_s) {
        s = 0.5 * seg->accel * seg->ramp_s * seg->ramp_s +
            seg->peak * (t - seg->ramp_s);
        v = seg->peak;
    } else {
        s = 1.0 - 0.5 * seg->accel * left * left;
        v = seg->accel * left;
    }
    if (ds)
        *ds = v;
    return s;
}

void qrtcan_segment_at(const struct qrtcan_segment *seg,
                       const double from[QRTCAN_JOINTS], double t,
                       double q[QRTCAN_JOINTS], double *vel)
{
    double ds = 0.0, s = qrtcan_segment_fraction(seg, t, &ds);
    int j;
    for (j = 0; j < QRTCAN_JOINTS; j++) {
        /* the end exactly where the step lands */
        q[j] = s >= 1.0 ? from[j] + seg->step_deg[j]
                        : from[j] + s * seg->step_deg[j];
        if (vel)
            vel[j] = ds * seg->step_deg[j];
    }
}

static uint32_t counts_rate(double deg_rate, double counts_per_deg,
                            double floor_deg)
{
    double v = (deg_rate > floor_deg ? deg_rate : floor_deg) * counts_per_deg;
    return v < 1.0 ? 1u : v > 4e9 ? 4000000000u : (uint32_t)(v + 0.5);
}

static void to_counts(const double vel_deg[QRTCAN_JOINTS],
                      const double acc_deg[QRTCAN_JOINTS],
                      const struct qrtcan_scale scale[QRTCAN_JOINTS],
                      uint32_t vel[QRTCAN_JOINTS], uint32_t acc[QRTCAN_JOINTS])
{
    int j;
    for (j = 0; j < QRTCAN_JOINTS; j++) {
        double c = fabs(scale[j].counts_per_deg);
        vel[j] = counts_rate(vel_deg[j], c, QRTCAN_FLOOR_SPEED_DEG_S);
        acc[j] = counts_rate(acc_deg[j], c, QRTCAN_FLOOR_ACCEL_DEG_S2);
    }
}

void qrtcan_segment_counts(const struct qrtcan_segment *seg,
                           const struct qrtcan_scale scale[QRTCAN_JOINTS],
                           uint32_t vel[QRTCAN_JOINTS],
                           uint32_t acc[QRTCAN_JOINTS])
{
    to_counts(seg->vel_deg_s, seg->accel_deg_s2, scale, vel, acc);
}

int qrtcan_segment_drive_profile(const double max_speed_deg_s[QRTCAN_JOINTS],
                                 const double max_accel_deg_s2[QRTCAN_JOINTS],
                                 const struct qrtcan_scale scale[QRTCAN_JOINTS],
                                 const double step_deg[QRTCAN_JOINTS],
                                 uint32_t vel[QRTCAN_JOINTS],
                                 uint32_t acc[QRTCAN_JOINTS])
{
    double speed, accel, vel_deg[QRTCAN_JOINTS], acc_deg[QRTCAN_JOINTS];
    int moves = rates(max_speed_deg_s, max_accel_deg_s2, step_deg, &speed,
                      &accel, vel_deg, acc_deg);
    if (moves < 0)
        return moves;
    to_counts(vel_deg, acc_deg, scale, vel, acc);
    return QRTCAN_OK;
}
