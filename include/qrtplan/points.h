/* The obstacle point table: the inspection points the planner avoids.
 *
 * Points are kept exactly while they fit. When more arrive than
 * QRT_MAX_POINTS, the points are merged by voxel on a grid of
 * QRT_VOXEL_BASE_M; if that still overflows, the voxel edge doubles, up to
 * QRT_VOXEL_MAX_M. A voxel's entry keeps the box of its members (on a
 * grid of QRT_VOXEL_BOX_STEPS steps a voxel edge, rounded outwards) and
 * stands at the box's centre, so the planner inflates every collision
 * radius by the largest box's half-diagonal: never more than the voxel's
 * half-diagonal, much less where the points lie on a surface, never
 * unsafe.
 * Only when even the coarsest voxels do not fit are points dropped, counted
 * in `dropped`, and the planner then refuses to plan (QRT_STATUS_CAPACITY).
 * Points farther from the base than any part of the arm can reach are
 * ignored (counted in `ignored_far`): they cannot block anything.
 */
#ifndef QRTPLAN_POINTS_H
#define QRTPLAN_POINTS_H

#include <stddef.h>
#include <stdint.h>

#include "qrtplan/config.h"

#ifdef __cplusplus
extern "C" {
#endif

#define QRT_VOXEL_BASE_M 0.001
#define QRT_VOXEL_MAX_M 0.064
#define QRT_POINT_HASH_SLOTS (2L * QRT_MAX_POINTS)
/* Steps of a merged entry's box along a voxel edge (a byte a bound). */
#define QRT_VOXEL_BOX_STEPS 255
/* far_min2 while no point has been ignored. */
#define QRT_NO_FAR_POINT 1e300

/* The entries are stored by axis, entry i at (x[i], y[i], z[i]): the
 * passes over every point (the intake's reach check, the one-pass proof's
 * off-sweep test) then read whole vectors of one axis, and the compiler
 * makes them 4 lanes wide. */
struct qrt_points {
    float x[QRT_MAX_POINTS], y[QRT_MAX_POINTS], z[QRT_MAX_POINTS];
    uint32_t hash[QRT_POINT_HASH_SLOTS]; /* voxel mode: entry index + 1 */
    /* voxel mode: entry i's box, its members' bounds along axis k in steps
     * of voxel_m / QRT_VOXEL_BOX_STEPS from its voxel's low corner (low
     * rounded down, high up, at least a step apart); the entry stands at
     * the box's centre */
    uint8_t box_lo[3][QRT_MAX_POINTS], box_hi[3][QRT_MAX_POINTS];
    double box_radius_m; /* voxel mode: the largest box's half-diagonal */
    long count;          /* entries in x, y, z */
    long received;       /* points passed to qrt_points_add since reset */
    long ignored_far;    /* beyond reach_m */
    long dropped;        /* lost to capacity: non-zero means do not plan */
    double voxel_m;      /* 0 while exact, else the voxel edge in use */
    double reach_m;      /* points farther than this are ignored */
    double far_min2;     /* least |p|^2 of the ignored points, or 1e300 */
};

/* Empty the table. reach_m: points with |p| > reach_m are ignored; pass
 * the arm's reach plus its largest collision radius (the planner does). */
void qrt_points_reset(struct qrt_points *pts, double reach_m);

/* Add n points (x, y, z in metres, 3n doubles). Returns QRT_OK, or
 * QRT_E_INVALID (nothing added) if any coordinate is NaN or infinite. */
int qrt_points_add(struct qrt_points *pts, const double *xyz, long n);

/* Radius every stored point stands for beyond its stored position: the
 * largest merged box's half-diagonal (at most the voxel's) plus the float
 * rounding of the stored position. */
double qrt_points_inflation_m(const struct qrt_points *pts);

/* Read-only views of a table's axes (or of any points kept by axis), for
 * the passes that read them: entry i at (x[i], y[i], z[i]). */
struct qrt_point_axes {
    const float *x, *y, *z;
};

static inline struct qrt_point_axes
qrt_points_axes(const struct qrt_points *pts)
{
    struct qrt_point_axes a;
    a.x = pts->x;
    a.y = pts->y;
    a.z = pts->z;
    return a;
}

/* Entry i of a, in double. */
static inline void qrt_point_at(const struct qrt_point_axes *a, long i,
                                double p[3])
{
    p[0] = a->x[i];
    p[1] = a->y[i];
    p[2] = a->z[i];
}

#ifdef __cplusplus
}
#endif
#endif
