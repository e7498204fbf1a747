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

int qrtcan_segment_profile(const double max_speed_deg_s[QRTCAN_JOINTS],
                           const double max_accel_deg_s2[QRTCAN_JOINTS],
                           const double step_deg[QRTCAN_JOINTS],
                           struct qrtcan_segment *seg)
{
    double speed = 1e300, accel = 1e300; /* path parameter per second */
    int j;
    for (j = 0; j < QRTCAN_JOINTS; j++)
        if (!(max_speed_deg_s[j] > 0.0) || !isfinite(max_speed_deg_s[j]) ||
            !(max_accel_deg_s2[j] > 0.0) || !isfinite(max_accel_deg_s2[j]) ||
            !isfinite(step_deg[j]))
            return QRTCAN_E_ARG;
    memset(seg, 0, sizeof *seg);
    for (j = 0; j < QRTCAN_JOINTS; j++) {
        seg->step_deg[j] = step_deg[j];
        if (fabs(step_deg[j]) < STILL_DEG)
            continue;
        seg->moves = 1;
        if (max_speed_deg_s[j] / fabs(step_deg[j]) < speed)
            speed = max_speed_deg_s[j] / fabs(step_deg[j]);
        if (max_accel_deg_s2[j] / fabs(step_deg[j]) < accel)
            accel = max_accel_deg_s2[j] / fabs(step_deg[j]);
    }
    for (j = 0; j < QRTCAN_JOINTS; j++) {
        int still = fabs(step_deg[j]) < STILL_DEG;
        seg->vel_deg_s[j] =
            still ? max_speed_deg_s[j] : fabs(step_deg[j]) * speed;
        seg->accel_deg_s2[j] =
            still ? max_accel_deg_s2[j] : fabs(step_deg[j]) * accel;
    }
    if (!seg->moves)
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

void qrtcan_segment_counts(const struct qrtcan_segment *seg,
                           const struct qrtcan_scale scale[QRTCAN_JOINTS],
                           uint32_t vel[QRTCAN_JOINTS],
                           uint32_t acc[QRTCAN_JOINTS])
{
    int j;
    for (j = 0; j < QRTCAN_JOINTS; j++) {
        double c = fabs(scale[j].counts_per_deg);
        vel[j] = counts_rate(seg->vel_deg_s[j], c, QRTCAN_FLOOR_SPEED_DEG_S);
        acc[j] =
            counts_rate(seg->accel_deg_s2[j], c, QRTCAN_FLOOR_ACCEL_DEG_S2);
    }
}
