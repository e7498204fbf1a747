/* NOT API. The layout of struct qrt_planner, here only so that callers can
 * allocate it statically (its size must be known where it is declared).
 * Nothing in this file is part of the interface: fields, types and macros
 * change without notice, and only the library reads or writes them. Use
 * the functions of qrtplan/planner.h; the terms are defined there. */
#ifndef QRTPLAN_PLANNER_INTERNAL_H
#define QRTPLAN_PLANNER_INTERNAL_H

#include <stdint.h>

#include "qrtplan/config.h"
#include "qrtplan/lattice.h"
#include "qrtplan/params.h"
#include "qrtplan/points.h"
#include "qrtplan/status.h"

#ifdef __cplusplus
extern "C" {
#endif

/* The node first and the key as its float's bits, so that the search
 * reads an entry's order as one 64-bit word where the target is
 * little-endian (src/core/search.c, heap_rank). */
struct qrti_heap_entry {
    int32_t node;
    uint32_t key_bits; /* cost so far plus the A* estimate */
};

/* A cluster, prepared once so that its cells can be rastered one alpha
 * node at a time (qrt_planner_plan_now). */
#define QRTI_ALPHA_WORDS ((QRT_MAX_NA + 63) / 64)
struct qrti_cluster_geom {
    double c[3], ball, rho; /* bounding ball (one point: itself, ball 0) */
    int32_t first, m;       /* its points: members[first .. first + m - 1] */
    uint64_t alpha[QRTI_ALPHA_WORDS]; /* alpha nodes it may block */
};

/* A disc in the arm's vertical plane at one alpha node (its centre from the
 * shoulder, radial and height) that link 3 must come within reach3 of to
 * touch a point or a cluster; reach3 < 0: link 3 cannot touch it there.
 * Floats, so that more of them fit: reach3 is rounded up by the centre's
 * rounding. */
struct qrti_disc {
    float cu, z, reach3;
};

/* A cluster's view at one alpha node: its bounding ball's disc, the sigma
 * rows link 3 may reach there (less those its link 2 blocks whole), and
 * where its members' discs are kept once a single-node query needed them
 * (-1: not kept). */
#define QRTI_SIGMA_WORDS ((QRT_MAX_NS + 63) / 64)
struct qrti_alpha_view {
    struct qrti_disc disc;
    uint64_t rows[QRTI_SIGMA_WORDS];
    int32_t cluster, members_at;
};

/* The clusters kept while the mask is partial live in the tail of the
 * heap array, which leaves QRTI_LAZY_HEAP entries for the heap; should the
 * heap need more, the rest of the mask is built and the clusters given
 * up. A point cloud with more clusters or points than fit is given a whole
 * mask instead. The table's bytes after the clusters hold views and member
 * discs (as many as fit; when full, they are forgotten and made again as
 * needed). */
#define QRTI_LAZY_MAX_CLUSTERS                                                 \
    (QRT_MAX_POINTS < QRT_MAX_NODES / 16 ? QRT_MAX_POINTS : QRT_MAX_NODES / 16)
#define QRTI_LAZY_MAX_POINTS                                                   \
    (QRT_MAX_POINTS < QRT_MAX_NODES / 8 ? QRT_MAX_POINTS : QRT_MAX_NODES / 8)
#define QRTI_LAZY_TABLE_BYTES                                                  \
    ((long)QRTI_LAZY_MAX_CLUSTERS * (long)sizeof(struct qrti_cluster_geom))
/* The kept clusters from its start; in the bytes they leave free, views
 * and member discs. */
union qrti_lazy_table {
    struct qrti_cluster_geom geom[QRTI_LAZY_MAX_CLUSTERS];
    struct qrti_alpha_view
        view[QRTI_LAZY_TABLE_BYTES / (long)sizeof(struct qrti_alpha_view)];
    struct qrti_disc
        disc[QRTI_LAZY_TABLE_BYTES / (long)sizeof(struct qrti_disc)];
    int32_t list[QRTI_LAZY_TABLE_BYTES / (long)sizeof(int32_t)];
    uint64_t row_views[QRTI_LAZY_TABLE_BYTES / (long)sizeof(uint64_t)];
};
struct qrti_lazy_clusters {
    union qrti_lazy_table t;
    double member_rho[QRTI_LAZY_MAX_POINTS]; /* each member's distance from
                                                the base axis */
    int32_t members[QRTI_LAZY_MAX_POINTS];
    /* bit per lattice node (index (ia * ns + is) * ne + ie): nodes of rows
     * not built yet whose bit a single-node query set (their mask bits are
     * final); kept with the clusters, in the heap's room */
    uint64_t known[(QRT_MAX_NODES + 63) / 64];
};
#define QRTI_LAZY_HEAP                                                         \
    (QRT_MAX_NODES - (long)((sizeof(struct qrti_lazy_clusters) +               \
                             sizeof(struct qrti_heap_entry) - 1) /             \
                            sizeof(struct qrti_heap_entry)))
#define QRTI_LAZY_NO_INDEX (-2147483647 - 1)

/* The goal region: the QRT_GOAL_REGION_NODES nodes nearest the goal, with
 * their exact cost to it, found by a short Dijkstra from the goal before
 * A* starts (perimeter search). A*'s estimate of a node outside them is
 * the least octile distance to one of its rim nodes plus that
 * node's cost, which knows how the goal must be entered (the paper's
 * 10-sphere goal sits in a gap between spheres). */
struct qrti_goal_region {
    int settled, rim; /* entries used below */
    int used; /* whether A* took its estimate (it said more at a seed) */
    int32_t node[QRT_GOAL_REGION_NODES]; /* every node settled */
    /* bit ia set: a settled node lies on alpha node ia (a node on any
     * other cannot be one of them, so A* skips the look-up) */
    uint64_t alpha[QRTI_ALPHA_WORDS];
    float cost[QRT_GOAL_REGION_NODES]; /* its exact cost to the goal */
    /* the rim: settled nodes with a free neighbour outside the region
     * (every path from outside enters through one): lattice
     * coordinates and cost in grid steps, in columns that A* reads whole
     * (a rim shorter than the table is padded with infinite costs) */
    float rim_a[QRT_GOAL_REGION_NODES], rim_s[QRT_GOAL_REGION_NODES],
        rim_e[QRT_GOAL_REGION_NODES], rim_steps[QRT_GOAL_REGION_NODES];
};

/* One pose (a stored configuration) of a straight motion that is being proved
 * free against the points themselves (the first thing a plan tries): cos and
 * sin of alpha, of sigma and of sigma + eta, and the elbow in the arm's plane.
 */
struct qrti_sweep_pose {
    double ca, sa, cs, ss, cp, sp, elbow_u, elbow_z;
};
/* How many: 256, or fewer where the search scratch they borrow is smaller. */
#define QRTI_SWEEP_POSES                                                       \
    (QRT_MAX_NODES >= 4096 ? 256 : QRT_MAX_NODES >= 2048 ? 128 : 64)

/* The clustering scratch of a whole build's parts, for a table of n
 * points: at most 5n/2 + 16 entries (src/core/cluster.c). The search's
 * node arrays, idle until the next search, lend it for a table that small
 * (a board's); a larger table (the host profile's) has its own, one a
 * part (there are at most two), and no table goes without clustering,
 * whose point-by-point fallback is many times slower. */
#define QRTI_CLUSTER_SCRATCH_LEN ((long)QRT_MAX_POINTS * 5 / 2 + 16)
#define QRTI_OWN_CLUSTER_SCRATCH                                               \
    (QRTI_CLUSTER_SCRATCH_LEN > QRT_MAX_NODES ? QRTI_CLUSTER_SCRATCH_LEN : 1)

struct qrt_raster; /* the conversion's tables (src/core/raster.h) */

/* Table entries a block box covers (the core's QRT_CLEARANCE_BLOCK), blocks
 * a group box covers, and how many boxes the table needs: one a block,
 * then one a group (src/core/motion.h, qrt_points_block_boxes). */
#define QRTI_POINT_BLOCK 64
#define QRTI_BLOCK_GROUP 64 /* the core's QRT_CLEARANCE_GROUP */
#define QRTI_POINT_BLOCKS                                                      \
    ((QRT_MAX_POINTS + QRTI_POINT_BLOCK - 1) / QRTI_POINT_BLOCK)
#define QRTI_BLOCK_BOXES                                                       \
    (QRTI_POINT_BLOCKS +                                                       \
     (QRTI_POINT_BLOCKS + QRTI_BLOCK_GROUP - 1) / QRTI_BLOCK_GROUP)

/* A configuration of the sampled fallback's trees (src/core/sampled.h). */
struct qrti_sampled_node {
    double q_deg[3];
    int32_t parent; /* -1 at a root */
    int32_t tree;   /* 0 grows from the start, 1 from the goal */
};
/* Nodes the fallback's trees may hold: 4096, or fewer where the search
 * scratch they borrow (4 bytes a lattice node) is smaller; each takes 36
 * bytes (itself and its place on a path), after the block boxes. */
#define QRTI_SAMPLED_ROOM                                                      \
    (((long)QRT_MAX_NODES * 4 - (long)QRTI_BLOCK_BOXES * 24) / 36)
#define QRTI_SAMPLED_NODES                                                     \
    (QRTI_SAMPLED_ROOM >= 4096 ? 4096                                          \
     : QRTI_SAMPLED_ROOM >= 2  ? QRTI_SAMPLED_ROOM                             \
                               : 2)

struct qrt_planner {
    struct qrt_params params;
    /* params.arm's collision arm (qrt_arm_collision_arm): every collision
     * check, the mask's and the points', uses it */
    struct qrt_arm collision_arm;
    struct qrt_points points;
    struct qrt_mask mask;
    double radius_m[3]; /* per-link collision radius the mask was built for */
    long cells_blocked;
    /* 1 once the table's entries are in Morton order (src/core/order.h),
     * until points are added or cleared */
    int points_ordered;
    /* what the mask holds for the points in the table; while a call builds
     * rows as it reads them (lazy_raster set) it is QRT_MASK_PARTIAL */
    enum qrt_mask_state mask_state;
    /* the mask rows qrt_planner_check_path_now builds */
    uint64_t check_rows[QRT_ROW_SET_WORDS];
    /* search scratch, one entry per lattice node; while a mask is built,
     * heap_pos and cluster_scratch are the clustering scratch of parts 0
     * and 1; before the search, the straight motion's poses
     * configurations */
    union {
        float dist[QRT_MAX_NODES];
        int32_t cluster_scratch[QRT_MAX_NODES];
        struct qrti_sweep_pose sweep[QRTI_SWEEP_POSES];
        /* while qrt_planner_certify_clearance runs: the box of each block
         * of QRTI_POINT_BLOCK table entries (its least x, y, z, then its
         * greatest), so that a block far from the arm is passed over
         * whole */
        float block_box[QRTI_BLOCK_BOXES][6];
        /* while the sampled fallback runs: the block boxes (the same
         * place), its trees and the path through them */
        struct {
            float block_box[QRTI_BLOCK_BOXES][6];
            struct qrti_sampled_node node[QRTI_SAMPLED_NODES];
            int32_t path[QRTI_SAMPLED_NODES];
        } sampled;
    } search;
    union {
        struct qrti_heap_entry heap[QRT_MAX_NODES]; /* later holds the path */
        struct {
            struct qrti_heap_entry heap[QRTI_LAZY_HEAP];
            struct qrti_lazy_clusters clusters;
        } lazy;
    } open;
    /* a node's place on the heap, -2 closed; valid only where the node's
     * search_seen bit is set (-1 unseen otherwise) */
    int32_t heap_pos[QRT_MAX_NODES];
    uint64_t search_seen[(QRT_MAX_NODES + 63) / 64];
    uint8_t parent_dir[QRT_MAX_NODES];
    struct qrti_goal_region goal_region; /* the last A* search's */
    long lazy_clusters;                  /* in open.lazy.clusters */
    /* the views and discs kept lie in the table from the clusters' end to
     * byte lazy_views_top; alpha node ia's views are the
     * lazy_alpha_count[ia] from view lazy_alpha_first[ia] (-1: none) */
    long lazy_views_top;
    int32_t lazy_alpha_first[QRT_MAX_NA], lazy_alpha_count[QRT_MAX_NA];
    /* alpha node ia's views by sigma row, once QRT_LAZY_INDEX_AFTER
     * single-node queries fell on it: from table entry
     * lazy_alpha_index[ia] (a row_views entry >= 0), a bit per view for
     * each row, the rows one after another; below 0, -1 minus the queries
     * so far, or QRTI_LAZY_NO_INDEX when it did not fit */
    int32_t lazy_alpha_index[QRT_MAX_NA];
    /* where they fit (lazy_lists), each alpha node's kept clusters (those
     * that may block it) are listed from table entry
     * lazy_alpha_list[ia] (int32s right after the clusters, up to byte
     * lazy_lists_end), lazy_alpha_clusters[ia] of them */
    int32_t lazy_alpha_list[QRT_MAX_NA], lazy_alpha_clusters[QRT_MAX_NA];
    long lazy_lists_end;
    int lazy_lists;
    /* since the clusters were kept: how often the views were all forgotten
     * for want of room, rows built without views (an alpha node's did not
     * fit at all) and member discs made without being kept */
    long lazy_forgets, lazy_unviewed_rows, lazy_unkept_discs;
    long lazy_nodes_asked; /* single-node queries (qrt_lazy_node_blocked) */
    /* set only while a call builds rows as it reads them: the raster on
     * that call's stack */
    struct qrt_raster *lazy_raster;
    uint64_t rows_ready[QRT_ROW_SET_WORDS];
    /* each part's clustering scratch where the node arrays are too small
     * for the table (else one unused entry a part); a row for each of the
     * QRT_MAX_MASK_PARTS (planner.h) */
    int32_t cluster_scratch[2][QRTI_OWN_CLUSTER_SCRATCH];
};

#ifdef __cplusplus
}
#endif
#endif
