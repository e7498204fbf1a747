#include "qrtcan/scale.h"

#include <stddef.h>

#include "qrtcan/frame.h"

/* No libm: the codec must link on targets without it. A value is finite
 * when it equals itself (not NaN) and is inside the double range. */
static int is_finite(double x)
{
    /* cppcheck takes the range test for always true: it knows no
     * infinities, which are what it is there to turn away */
    /* cppcheck-suppress incorrectLogicOperator */
    return x == x && x <= 1.7976931348623157e308 &&
           x >= -1.7976931348623157e308;
}

int qrtcan_deg_to_counts(const struct qrtcan_scale *s, double deg,
                         int32_t *counts)
{
    double c;
    if (s == NULL || counts == NULL || !is_finite(s->counts_per_deg) ||
        s->counts_per_deg == 0.0) {
        return QRTCAN_E_ARG;
    }
    if (!is_finite(deg)) {
        return QRTCAN_E_RANGE;
    }
    c = deg * s->counts_per_deg + (double)s->offset_counts;
    /* compare before converting: an out-of-range conversion is undefined */
    if (!is_finite(c) || c >= 2147483647.5 || c <= -2147483648.5) {
        return QRTCAN_E_RANGE;
    }
    *counts = c >= 0.0 ? (int32_t)(c + 0.5) : (int32_t)(c - 0.5);
    return QRTCAN_OK;
}

int qrtcan_counts_to_deg(const struct qrtcan_scale *s, int32_t counts,
                         double *deg)
{
    if (s == NULL || deg == NULL || !is_finite(s->counts_per_deg) ||
        s->counts_per_deg == 0.0) {
        return QRTCAN_E_ARG;
    }
    *deg = ((double)counts - (double)s->offset_counts) / s->counts_per_deg;
    return QRTCAN_OK;
}

int qrtcan_joints_to_counts(const struct qrtcan_scale s[3], const double deg[3],
                            int32_t counts[3])
{
    int i, rc;
    if (s == NULL || deg == NULL || counts == NULL) {
        return QRTCAN_E_ARG;
    }
    for (i = 0; i < 3; i++) {
        rc = qrtcan_deg_to_counts(&s[i], deg[i], &counts[i]);
        if (rc != QRTCAN_OK) {
            return rc;
        }
    }
    return QRTCAN_OK;
}

int qrtcan_counts_to_joints(const struct qrtcan_scale s[3],
                            const int32_t counts[3], double deg[3])
{
    int i, rc;
    if (s == NULL || deg == NULL || counts == NULL) {
        return QRTCAN_E_ARG;
    }
    for (i = 0; i < 3; i++) {
        rc = qrtcan_counts_to_deg(&s[i], counts[i], &deg[i]);
        if (rc != QRTCAN_OK) {
            return rc;
        }
    }
    return QRTCAN_OK;
}
