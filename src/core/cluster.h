/* Grouping nearby points, so the raster can share work among them.
 * Internal. */
#ifndef QRT_CORE_CLUSTER_H
#define QRT_CORE_CLUSTER_H

#include <stdint.h>

#include "qrtplan/points.h"
#include "tuning.h"

/* Points are grouped in cubes of edge QRT_CLUSTER_CELL_M (tuning.h); where
 * they lie so far apart that fewer than QRT_CLUSTER_SPARSE_MEAN fall in a
 * group on average, the cubes are made twice as large. */

typedef void (*qrt_cluster_visit)(void *ctx, const int32_t *members, int m);

/* Scratch entries qrt_cluster_points needs for n points. */
long qrt_cluster_scratch_len(long n);

/* Call visit once per group of points that share a cube of edge cell_m
 * (a cube's points come in groups of at most max_members), each point in
 * exactly one group. scratch holds qrt_cluster_scratch_len(n) entries. */
void qrt_cluster_points(const struct qrt_point_axes *ax, long n, double cell_m,
                        int max_members, int32_t *scratch,
                        qrt_cluster_visit visit, void *ctx);

/* The cube edge for n points that make `groups` groups in cubes of
 * QRT_CLUSTER_CELL_M (both builds of the mask take the same). */
double qrt_cluster_cell_for(long n, long groups);

/* How many groups qrt_cluster_points makes (the same arguments, no visit). */
long qrt_cluster_count(const struct qrt_point_axes *ax, long n, double cell_m,
                       int max_members, int32_t *scratch);

#endif
