/* Grouping nearby points, so the raster can share work among them.
 * Internal. */
#ifndef QRT_CORE_CLUSTER_H
#define QRT_CORE_CLUSTER_H

#include <stdint.h>

/* Edge of the cubes that group points for the raster: larger groups share
 * more work, but their bounding balls are less often already covered. */
#ifndef QRT_CLUSTER_CELL_M
#define QRT_CLUSTER_CELL_M 0.04
#endif

typedef void (*qrt_cluster_visit)(void *ctx, const int32_t *members, int m);

/* Scratch entries qrt_cluster_points needs for n points. */
long qrt_cluster_scratch_len(long n);

/* Call visit once per group of points that share a cube of edge cell_m
 * (a cube's points come in groups of at most max_members), each point in
 * exactly one group. scratch holds qrt_cluster_scratch_len(n) entries. */
void qrt_cluster_points(const float (*pts)[3], long n, double cell_m,
                        int max_members, int32_t *scratch,
                        qrt_cluster_visit visit, void *ctx);

#endif
