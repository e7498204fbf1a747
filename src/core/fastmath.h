/* Fast angle functions with a known error bound, for the raster's inner
 * loop. Every caller widens its angular intervals by QRT_FAST_ANGLE_ERR, so
 * the approximation can only make the blocked set larger. The bound is
 * checked against libm over dense samples in tests/unit/test_fastmath.c.
 * Internal. */
#ifndef QRT_CORE_FASTMATH_H
#define QRT_CORE_FASTMATH_H

#include <math.h>

#include "geom.h"

/* Upper bound on |qrt_fast_atan2(y, x) - atan2(y, x)| in radians. */
#define QRT_FAST_ANGLE_ERR 2e-5

/* atan on [0, 1]: odd minimax polynomial, error below 1e-5 rad. */
static inline double qrt_fast_atan01(double t)
{
    double t2 = t * t;
    return t * (0.99986601 +
                t2 * (-0.3302995 +
                      t2 * (0.1801410 + t2 * (-0.0851330 + t2 * 0.0208351))));
}

/* atan2 by octant reduction; atan2(0, 0) is 0 like libm's. */
static inline double qrt_fast_atan2(double y, double x)
{
    double ax = fabs(x), ay = fabs(y), r;
    if (ax == 0.0 && ay == 0.0)
        return 0.0;
    if (ay <= ax)
        r = qrt_fast_atan01(ay / ax);
    else
        r = 0.5 * QRT_PI - qrt_fast_atan01(ax / ay);
    if (x < 0.0)
        r = QRT_PI - r;
    return y < 0.0 ? -r : r;
}

#endif
