/* Small geometric helpers shared inside the core (not public API). */
#ifndef QRT_CORE_GEOM_H
#define QRT_CORE_GEOM_H

#include <math.h>

#include "qrtplan/joints.h"

#define QRT_PI 3.14159265358979323846
#define QRT_DEG (QRT_PI / 180.0)

/* x reduced to (-pi, pi]. */
static inline double qrt_wrap_rad(double x)
{
    double r = fmod(x, 2.0 * QRT_PI);
    if (r <= -QRT_PI)
        r += 2.0 * QRT_PI;
    else if (r > QRT_PI)
        r -= 2.0 * QRT_PI;
    return r;
}

/* floor and ceil for |x| < 2^31 without a libm call (x86-64 has no
 * rounding instruction before SSE4.1, so libm's are real calls). */
static inline long qrt_floor(double x)
{
    long i = (long)x;
    return i - (x < (double)i);
}

static inline long qrt_ceil(double x)
{
    long i = (long)x;
    return i + (x > (double)i);
}

/* Squared distance from point p to segment a-b in 3-D. */
static inline double qrt_seg_dist2(const double p[3], const double a[3],
                                   const double b[3])
{
    double ab[3], ap[3], t, len2, d2 = 0.0;
    int i;
    for (i = 0; i < 3; i++) {
        ab[i] = b[i] - a[i];
        ap[i] = p[i] - a[i];
    }
    len2 = ab[0] * ab[0] + ab[1] * ab[1] + ab[2] * ab[2];
    t = len2 > 0.0 ? (ap[0] * ab[0] + ap[1] * ab[1] + ap[2] * ab[2]) / len2
                   : 0.0;
    if (t < 0.0)
        t = 0.0;
    else if (t > 1.0)
        t = 1.0;
    for (i = 0; i < 3; i++) {
        double d = ap[i] - t * ab[i];
        d2 += d * d;
    }
    return d2;
}

#endif
