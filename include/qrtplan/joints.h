/* The arm's joints as every part sees them, the core and the programs
 * that do not link it (the CAN master, the simulated drives) alike: the
 * default limits and how a wrapping alpha's angles are taken (docs/spec.md
 * section Arm). Header only. */
#ifndef QRTPLAN_JOINTS_H
#define QRTPLAN_JOINTS_H

#include <math.h>

#ifdef __cplusplus
extern "C" {
#endif

/* [joint][lo, hi] in degrees, alpha's the whole circle (so it wraps), as an
 * initializer: the one definition of the default limits. */
/* clang-format off */
#define QRT_ARM_DEFAULT_LIMIT_DEG \
    {{-180.0, 180.0}, {-40.0, 180.0}, {-180.0, 140.0}}
/* clang-format on */

/* Whether alpha, with limits lim_deg [lo, hi], wraps (and has no limit):
 * exactly when they are the whole circle. */
static inline int qrt_alpha_wraps(const double lim_deg[2])
{
    return lim_deg[0] == -180.0 && lim_deg[1] == 180.0;
}

/* deg reduced to (-180, 180]: a wrapping alpha's angles and steps, the
 * short way round. */
static inline double qrt_wrap_deg(double deg)
{
    double r = fmod(deg, 360.0);
    if (r <= -180.0)
        r += 360.0;
    else if (r > 180.0)
        r -= 360.0;
    return r;
}

#ifdef __cplusplus
}
#endif
#endif
