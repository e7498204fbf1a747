/* Joint degrees <-> drive position counts, one linear scale per joint:
 * counts = offset + round(deg * counts_per_deg). The drive knows only
 * counts; the planner only degrees (docs/spec.md section Conventions:
 * degrees at every interface).
 */
#ifndef QRTCAN_SCALE_H
#define QRTCAN_SCALE_H

#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

struct qrtcan_scale {
    double counts_per_deg; /* non-zero, finite; negative flips direction */
    int32_t offset_counts; /* counts at 0 degrees */
};

/* QRTCAN_E_RANGE for NaN, infinities and results outside int32;
 * QRTCAN_E_ARG for a zero or non-finite scale. Rounds half away from 0. */
int qrtcan_deg_to_counts(const struct qrtcan_scale *s, double deg,
                         int32_t *counts);
int qrtcan_counts_to_deg(const struct qrtcan_scale *s, int32_t counts,
                         double *deg);

/* Three joints (alpha, sigma, eta) at once; stops at the first error. */
int qrtcan_joints_to_counts(const struct qrtcan_scale s[3], const double deg[3],
                            int32_t counts[3]);
int qrtcan_counts_to_joints(const struct qrtcan_scale s[3],
                            const int32_t counts[3], double deg[3]);

#ifdef __cplusplus
}
#endif

#endif
