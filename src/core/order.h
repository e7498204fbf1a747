/* The point table in space-filling-curve order. Internal.
 *
 * Checks against the exact points pass over whole blocks of
 * QRT_CLEARANCE_BLOCK consecutive entries that lie far from the arm
 * (motion.h, qrt_points_block_boxes); that pays only when a block's
 * entries lie close together. Points arrive in whatever order a sensor or
 * a file gives them, so the table is put in Morton order (the bits of the
 * three cell coordinates interleaved), in which entries that follow each
 * other lie in nearby cells at every scale. Which point sits where in the
 * table changes no answer of the planner, only how soon it is found. */
#ifndef QRT_CORE_ORDER_H
#define QRT_CORE_ORDER_H

#include <stdint.h>

#include "qrtplan/points.h"

/* int32 entries each of qrt_points_order's two scratch arrays needs for
 * n entries. */
long qrt_points_order_scratch_len(long n);

/* Put the table's entries (and in voxel mode their boxes and hash) in
 * Morton order of cells of the table's reach. scratch_a, scratch_b: two
 * arrays of qrt_points_order_scratch_len(pts->count) entries each; on
 * return scratch_a[i] is the new place of the entry that was at i. */
void qrt_points_order(struct qrt_points *pts, int32_t *scratch_a,
                      int32_t *scratch_b);

#endif
