/* The planner: points in, a safe joint path out.
 *
 * All state lives in struct qrt_planner, whose size is fixed at compile time
 * (under 4 MiB at the default 5 degree lattice). The caller owns it:
 * declare it static, or place it where the board's linker script says.
 *
 *   static struct qrt_planner pl;
 *   struct qrt_params prm;  qrt_params_default(&prm);
 *   qrt_planner_init(&pl, &prm);                 // arm, margins, lattice
 *   qrt_planner_add_points(&pl, xyz, n);         // as often as needed
 *   qrt_planner_build_mask(&pl);                 // points -> C-space mask
 *   qrt_planner_plan(&pl, &start, &goal, &plan); // mask -> path
 *
 * A mask can serve many plans; adding points after building needs another
 * build (qrt_planner_plan refuses a stale mask with QRT_E_INVALID).
 */
#ifndef QRTPLAN_PLANNER_H
#define QRTPLAN_PLANNER_H

#include <stddef.h>
#include <stdint.h>

#include "qrtplan/arm.h"
#include "qrtplan/config.h"
#include "qrtplan/lattice.h"
#include "qrtplan/points.h"
#include "qrtplan/status.h"

#ifdef __cplusplus
extern "C" {
#endif

struct qrt_params {
    struct qrt_arm arm;
    double margin_m;          /* workspace margin added to every radius */
    double cspace_margin_deg; /* Eq. 12 boundary expansion, every joint */
    double grid_deg;          /* lattice spacing */
    int use_astar;            /* 1: A* (same cost as Dijkstra), 0: Dijkstra */
    int simplify;             /* 1: shortcut the lattice path */
};

/* The defaults of docs/spec.md: margin 0.01 m, C-space margin 0, 5 degrees,
 * A*, simplification on. */
void qrt_params_default(struct qrt_params *params);

enum qrt_target_kind { QRT_TARGET_JOINTS = 0, QRT_TARGET_XYZ = 1 };

struct qrt_target {
    enum qrt_target_kind kind;
    double value[3]; /* joints in degrees, or an end-effector point in metres */
};

struct qrt_plan {
    enum qrt_plan_status status;
    const char *detail; /* one English sentence on the status */
    int n_waypoints;    /* > 0 only when status is QRT_STATUS_OK */
    double waypoints_deg[QRT_MAX_WAYPOINTS][3];
    double cost_deg;         /* length of the returned path */
    double lattice_cost_deg; /* optimal cost through the lattice, including
                                the start and goal connections */
    double start_deg[3];     /* the start and goal as joints (after IK) */
    double goal_deg[3];
    long start_node, goal_node; /* lattice nodes the path enters and leaves */
    long lattice_path_nodes;
    long nodes_expanded;
    long cells_blocked;
    long points, points_ignored, points_dropped;
    double voxel_m; /* 0 while points are exact */
};

/* The node first and the key as its float's bits, so that the search
 * reads an entry's order as one 64-bit word where the target is
 * little-endian (src/core/search.c, heap_rank). */
struct qrt_heap_entry {
    int32_t node;
    uint32_t key_bits; /* cost so far plus the A* estimate */
};

/* A cluster of nearby points, prepared once so that its cells can be
 * rastered one alpha node at a time (qrt_planner_plan_now). */
#define QRT_ALPHA_WORDS ((QRT_MAX_NA + 63) / 64)
struct qrt_cluster_geom {
    double c[3], ball, rho; /* bounding ball (one point: itself, ball 0) */
    int32_t first, m;       /* its points: members[first .. first + m - 1] */
    uint64_t alpha[QRT_ALPHA_WORDS]; /* alpha nodes it may block */
};

/* A disc in the arm's vertical plane at one alpha node (its centre from the
 * shoulder, radial and height) that link 3 must come within reach3 of to
 * touch a point or a cluster; reach3 < 0: link 3 cannot touch it there.
 * Floats, so that more of them fit: reach3 is rounded up by the centre's
 * rounding. */
struct qrt_disc {
    float cu, z, reach3;
};

/* What a cluster looks like at one alpha node, kept while rows are built as
 * they are read: its bounding ball's disc, the sigma rows link 3 may reach
 * there (less those its link 2 blocks whole), and where its members' discs
 * are kept once they have been asked for (-1: not kept). */
#define QRT_SIGMA_WORDS ((QRT_MAX_NS + 63) / 64)
struct qrt_alpha_view {
    struct qrt_disc disc;
    uint64_t rows[QRT_SIGMA_WORDS];
    int32_t cluster, members_at;
};

/* The clusters qrt_planner_plan_now keeps while it searches, in the tail of
 * the heap array: at most 11 bytes of every 16 (QRT_LAZY_HEAP entries stay
 * for the heap; should it need more, the rest of the mask is built and the
 * clusters given up). More clusters or points than this: the whole mask is
 * built first instead. The slots the clusters leave free keep their views
 * of the alpha nodes rows are built on (as many as fit; when they are full,
 * the views are forgotten and made again as needed). */
#define QRT_LAZY_MAX_CLUSTERS                                                  \
    (QRT_MAX_POINTS < QRT_MAX_NODES / 16 ? QRT_MAX_POINTS : QRT_MAX_NODES / 16)
#define QRT_LAZY_MAX_POINTS                                                    \
    (QRT_MAX_POINTS < QRT_MAX_NODES / 8 ? QRT_MAX_POINTS : QRT_MAX_NODES / 8)
#define QRT_LAZY_TABLE_BYTES                                                   \
    ((long)QRT_LAZY_MAX_CLUSTERS * (long)sizeof(struct qrt_cluster_geom))
/* The kept clusters from its start; in the bytes they leave free, views
 * and member discs. */
union qrt_lazy_table {
    struct qrt_cluster_geom geom[QRT_LAZY_MAX_CLUSTERS];
    struct qrt_alpha_view
        view[QRT_LAZY_TABLE_BYTES / (long)sizeof(struct qrt_alpha_view)];
    struct qrt_disc disc[QRT_LAZY_TABLE_BYTES / (long)sizeof(struct qrt_disc)];
    int32_t list[QRT_LAZY_TABLE_BYTES / (long)sizeof(int32_t)];
    uint64_t row_views[QRT_LAZY_TABLE_BYTES / (long)sizeof(uint64_t)];
};
struct qrt_lazy_clusters {
    union qrt_lazy_table t;
    double member_rho[QRT_LAZY_MAX_POINTS]; /* each member's distance from
                                               the base axis */
    int32_t members[QRT_LAZY_MAX_POINTS];
    /* bit per lattice node (index (ia * ns + is) * ne + ie): nodes of rows
     * not built yet that were asked one at a time (their mask bits are
     * final); kept with the clusters, in the heap's room */
    uint64_t known[(QRT_MAX_NODES + 63) / 64];
};
#define QRT_LAZY_HEAP                                                          \
    (QRT_MAX_NODES - (long)((sizeof(struct qrt_lazy_clusters) +                \
                             sizeof(struct qrt_heap_entry) - 1) /              \
                            sizeof(struct qrt_heap_entry)))
/* An alpha node's views are indexed by sigma row once this many of its
 * nodes have been asked alone (see lazy_alpha_index). */
#ifndef QRT_LAZY_INDEX_AFTER
#define QRT_LAZY_INDEX_AFTER 16
#endif
#define QRT_LAZY_NO_INDEX (-2147483647 - 1)

/* The nodes nearest the goal, with their exact cost to it, found by a
 * short Dijkstra from the goal before A* starts (perimeter search): A*'s
 * estimate of a node outside them is the least octile distance to one of
 * their rim nodes plus that node's cost, which knows how the goal must be
 * entered (the paper's 10-sphere goal sits in a gap between spheres). */
#ifndef QRT_GOAL_REGION_NODES
#define QRT_GOAL_REGION_NODES 12
#endif
#if QRT_GOAL_REGION_NODES < 4 || QRT_GOAL_REGION_NODES % 4 != 0
#error "QRT_GOAL_REGION_NODES must be a multiple of 4 (A* reads it in lanes)"
#endif
struct qrt_goal_region {
    int settled, rim; /* entries used below */
    int used; /* whether A* took its estimate (it said more at a seed) */
    int32_t node[QRT_GOAL_REGION_NODES]; /* every node settled */
    /* bit ia set: a settled node lies on alpha node ia (a node on any
     * other cannot be one of them, so A* skips the look-up) */
    uint64_t alpha[QRT_ALPHA_WORDS];
    float cost[QRT_GOAL_REGION_NODES]; /* its exact cost to the goal */
    /* the settled nodes with a free neighbour outside the region (every
     * path from outside enters through one): lattice coordinates and cost
     * in grid steps, in columns that A* reads whole (a rim shorter than
     * the table is padded with infinite costs) */
    float rim_a[QRT_GOAL_REGION_NODES], rim_s[QRT_GOAL_REGION_NODES],
        rim_e[QRT_GOAL_REGION_NODES], rim_steps[QRT_GOAL_REGION_NODES];
};

/* One stored configuration of a straight motion that is being proved free
 * against the points themselves (the first thing a plan tries): cos and sin
 * of alpha, of sigma and of sigma + eta, and the elbow in the arm's plane. */
struct qrt_sweep_leaf {
    double ca, sa, cs, ss, cp, sp, elbow_u, elbow_z;
};
/* How many: 256, or fewer where the search scratch they borrow is smaller. */
#define QRT_SWEEP_LEAVES                                                       \
    (QRT_MAX_NODES >= 4096 ? 256 : QRT_MAX_NODES >= 2048 ? 128 : 64)

struct qrt_raster; /* internal: the conversion's tables */

struct qrt_planner {
    struct qrt_params params;
    struct qrt_points points;
    struct qrt_mask mask;
    double radius_m[3]; /* per-link collision radius the mask was built for */
    long cells_blocked;
    int mask_stale; /* points changed since the mask was built */
    /* the mask rows qrt_planner_check_path_now builds */
    uint64_t check_rows[QRT_ROW_SET_WORDS];
    /* search scratch, one entry per lattice node; while a mask is built,
     * heap_pos and cluster_scratch are the clustering scratch of parts 0
     * and 1; before the search, the straight motion's configurations */
    union {
        float dist[QRT_MAX_NODES];
        int32_t cluster_scratch[QRT_MAX_NODES];
        struct qrt_sweep_leaf sweep[QRT_SWEEP_LEAVES];
    } search;
    union {
        struct qrt_heap_entry heap[QRT_MAX_NODES]; /* later holds the path */
        struct {
            struct qrt_heap_entry heap[QRT_LAZY_HEAP];
            struct qrt_lazy_clusters clusters;
        } lazy;
    } open;
    /* a node's place on the heap, -2 closed; valid only where the node's
     * search_seen bit is set (-1 unseen otherwise) */
    int32_t heap_pos[QRT_MAX_NODES];
    uint64_t search_seen[(QRT_MAX_NODES + 63) / 64];
    uint8_t parent_dir[QRT_MAX_NODES];
    struct qrt_goal_region goal_region; /* the last A* search's */
    /* while qrt_planner_plan_now runs: rows are built as they are read */
    int lazy;
    /* the kept clusters and the rows_ready rows are still those of the
     * points in the table (after qrt_planner_check_path_now or _plan_now),
     * so the next qrt_planner_plan_now starts from them */
    int lazy_kept;
    long lazy_clusters; /* in open.lazy.clusters */
    /* the views and discs kept lie in the table from the clusters' end to
     * byte lazy_views_top; alpha node ia's views are the
     * lazy_alpha_count[ia] from view lazy_alpha_first[ia] (-1: none) */
    long lazy_views_top;
    int32_t lazy_alpha_first[QRT_MAX_NA], lazy_alpha_count[QRT_MAX_NA];
    /* alpha node ia's views by sigma row, once QRT_LAZY_INDEX_AFTER of its
     * nodes have been asked alone: from table entry lazy_alpha_index[ia]
     * (a row_views entry >= 0), a bit per view for each row, the rows one
     * after another; below 0, -1 minus the nodes asked so far, or
     * QRT_LAZY_NO_INDEX when it did not fit */
    int32_t lazy_alpha_index[QRT_MAX_NA];
    /* where they fit (lazy_lists), each alpha node's kept clusters (those
     * whose window holds it) are listed from table entry
     * lazy_alpha_list[ia] (int32s right after the clusters, up to byte
     * lazy_lists_end), lazy_alpha_clusters[ia] of them */
    int32_t lazy_alpha_list[QRT_MAX_NA], lazy_alpha_clusters[QRT_MAX_NA];
    long lazy_lists_end;
    int lazy_lists;
    /* since the clusters were kept: how often the views were all forgotten
     * for want of room, rows built without views (an alpha node's did not
     * fit at all) and member discs made without being kept */
    long lazy_forgets, lazy_unviewed_rows, lazy_unkept_discs;
    long lazy_nodes_asked; /* nodes asked alone (qrt_lazy_node_blocked) */
    struct qrt_raster *lazy_raster; /* on qrt_planner_plan_now's stack */
    uint64_t rows_ready[QRT_ROW_SET_WORDS];
};

/* The ABI guard. The sizes of struct qrt_planner and struct qrt_plan come
 * from the compile-time settings above, which the caller's compiler reads
 * in these headers and the library's compiler read when the library was
 * built. Should they differ (a program compiled with -DQRT_MAX_POINTS=1024
 * against a library built with 16384), the library would write its larger
 * layout into the caller's smaller struct and overrun it. So every caller
 * describes its own build to the library (qrt_planner_init below does it
 * for you), and the library refuses, before it touches the planner, a
 * build that is not its own. The record holds only longs, so its layout
 * does not depend on the settings it reports; abi_bytes comes first so
 * that a record from another version's headers is told apart by it
 * alone. */
struct qrt_abi {
    long abi_bytes;         /* sizeof(struct qrt_abi) */
    long grid_deg_min;      /* QRT_GRID_DEG_MIN */
    long max_points;        /* QRT_MAX_POINTS */
    long max_waypoints;     /* QRT_MAX_WAYPOINTS (struct qrt_plan only) */
    long goal_region_nodes; /* QRT_GOAL_REGION_NODES */
    long lazy_index_after;  /* QRT_LAZY_INDEX_AFTER (behaviour only) */
    /* the same settings can still be laid out differently by another
     * compiler or ABI option (packing, -fshort-enums) */
    long planner_bytes; /* sizeof(struct qrt_planner) */
    long plan_bytes;    /* sizeof(struct qrt_plan) */
    long enum_bytes;    /* sizeof(enum qrt_plan_status) */
};

/* The build of the code this is compiled into: the caller's in the
 * caller's code, the library's in the library's. */
static inline struct qrt_abi qrt_abi_here(void)
{
    struct qrt_abi abi;
    abi.abi_bytes = (long)sizeof(struct qrt_abi);
    abi.grid_deg_min = (long)QRT_GRID_DEG_MIN;
    abi.max_points = (long)QRT_MAX_POINTS;
    abi.max_waypoints = (long)QRT_MAX_WAYPOINTS;
    abi.goal_region_nodes = (long)QRT_GOAL_REGION_NODES;
    abi.lazy_index_after = (long)QRT_LAZY_INDEX_AFTER;
    abi.planner_bytes = (long)sizeof(struct qrt_planner);
    abi.plan_bytes = (long)sizeof(struct qrt_plan);
    abi.enum_bytes = (long)sizeof(enum qrt_plan_status);
    return abi;
}

/* Room for the longest sentence qrt_abi_check writes, with its zero; it
 * writes no more than this. */
#define QRT_ABI_MESSAGE_LEN 512

/* QRT_OK when the build *caller describes is the library's; else QRT_E_ABI
 * and, when msg is not NULL, one sentence in msg (at most msg_len bytes
 * with the terminating zero; cut short, never overrun, when it does not
 * fit) naming each setting that differs with the caller's and the
 * library's value, e.g. "the caller was built with QRT_MAX_POINTS 1024,
 * the library with 16384"; the sizes are named only when every setting
 * agrees. msg is "" when the builds agree. No allocation, no I/O. */
int qrt_abi_check(const struct qrt_abi *caller, char *msg, size_t msg_len);

/* Why qrt_planner_init returned QRT_E_ABI, for the code this is compiled
 * into: qrt_abi_check's sentence in msg, which it returns. */
static inline const char *qrt_abi_message(char *msg, size_t msg_len)
{
    struct qrt_abi abi = qrt_abi_here();
    (void)qrt_abi_check(&abi, msg, msg_len);
    return msg;
}

/* QRT_OK; QRT_E_ABI, with *pl untouched, when *caller is not the library's
 * build (see struct qrt_abi); QRT_E_INVALID for non-finite or negative
 * margins, a bad arm or a bad grid; QRT_E_TOO_BIG when the lattice exceeds
 * this build. Call it through qrt_planner_init. */
int qrt_planner_init_abi(struct qrt_planner *pl,
                         const struct qrt_params *params,
                         const struct qrt_abi *caller);

/* qrt_planner_init_abi with the build of the code this is compiled into:
 * an inline function of the header, not of the library, so that the sizes
 * and settings it passes are the caller's. */
static inline int qrt_planner_init(struct qrt_planner *pl,
                                   const struct qrt_params *params)
{
    struct qrt_abi abi = qrt_abi_here();
    return qrt_planner_init_abi(pl, params, &abi);
}

/* Forget every point (the arm and lattice stay). */
void qrt_planner_clear_points(struct qrt_planner *pl);

/* Add n points (3n doubles, metres, base frame); see points.h. */
int qrt_planner_add_points(struct qrt_planner *pl, const double *xyz, long n);

/* Convert the points into the C-space mask (paper blocks b-f). */
int qrt_planner_build_mask(struct qrt_planner *pl);

/* The same conversion split for several cores: call _begin, then
 * _part(pl, k, nparts) for every k in 0..nparts-1 (nparts <=
 * QRT_MAX_MASK_PARTS), at the same time on different threads if you like
 * (each part writes only its own alpha slices of the mask and its own
 * scratch), then _end once they have all returned. The mask is bit for bit
 * the one qrt_planner_build_mask makes. _part returns QRT_E_INVALID for a
 * bad part or count. */
#define QRT_MAX_MASK_PARTS 2
int qrt_planner_build_mask_begin(struct qrt_planner *pl);
int qrt_planner_build_mask_part(struct qrt_planner *pl, int part, int nparts);
int qrt_planner_build_mask_end(struct qrt_planner *pl);

/* Plan from start to goal on the built mask (paper blocks g-h). With
 * shortcuts on (params.simplify), every plan first tries the straight
 * motion between the ends' first joints (the target's, or its IK branch
 * nearest the other end) against the points themselves, in one pass over
 * them; when that proves it free, it is the plan. Returns
 * QRT_OK with the outcome in plan->status, or QRT_E_LIMITS when joints are
 * outside the limits, QRT_E_INVALID for NaN/Inf or a stale mask. */
int qrt_planner_plan(struct qrt_planner *pl, const struct qrt_target *start,
                     const struct qrt_target *goal, struct qrt_plan *plan);

/* qrt_planner_build_mask and qrt_planner_plan in one, with less work: the
 * plan is the same (the same waypoints, cost and nodes expanded). A
 * straight motion proved against the points needs no mask node at all;
 * otherwise only the mask nodes the plan reads are found, as the search, the
 * start and goal connections and the shortcuts read them: one node at a time
 * where the sector test holds (every grid under 90 degrees), each with the bit
 * the whole mask gives it, else a row at a time. plan->cells_blocked is -1 (the
 * whole mask was not built), and the mask is left partial: a later
 * qrt_planner_plan or qrt_planner_check_path needs qrt_planner_build_mask
 * first. Same return codes as qrt_planner_plan, without the stale mask.
 *
 * The nodes and rows it finds, and the rows qrt_planner_check_path_now and
 * qrt_planner_plan_straight build, are kept with the points' clusters
 * until the points change (or a whole mask or plain qrt_planner_plan needs
 * the room): each of these three calls on the same points goes on from
 * what the last one built, so a replan may check the path being executed
 * and plan anew, in either order, for little more than the plan. */
int qrt_planner_plan_now(struct qrt_planner *pl, const struct qrt_target *start,
                         const struct qrt_target *goal, struct qrt_plan *plan);

/* The shortcut of an open scene, before any mask is built: with joint
 * targets, tests the straight motion from start to goal as qrt_planner_plan
 * does (against the points, then on the mask rows it passes through, which
 * are built only if the first test fails). Returns 1
 * with *plan the straight motion (status ok, cells_blocked -1: the mask was
 * not built), or 0: call qrt_planner_build_mask and qrt_planner_plan (also
 * for xyz targets, simplification off, or points lost to capacity); or
 * QRT_E_INVALID / QRT_E_LIMITS for bad targets. Either way the mask is left
 * partial, so a later qrt_planner_plan needs qrt_planner_build_mask first. */
int qrt_planner_plan_straight(struct qrt_planner *pl,
                              const struct qrt_target *start,
                              const struct qrt_target *goal,
                              struct qrt_plan *plan);

/* Is a path still safe on the built mask (a replan's question about the
 * path being executed)? *first_blocked is the index of the first segment
 * (waypoint i to i+1) that cannot be proved free, or -1 if every segment is
 * (same certificate as the planner's own motions: the mask walk, else
 * conservative advancement against the points); 0 when points were lost
 * to capacity, since then nothing can be proved. QRT_E_INVALID for a stale
 * mask, n < 1 or NaN/Inf; QRT_E_LIMITS for a waypoint outside the limits. */
int qrt_planner_check_path(const struct qrt_planner *pl,
                           const double (*waypoints_deg)[3], int n,
                           int *first_blocked);

/* The same question asked of the points now in the table, before any mask
 * is built for them: builds only the mask rows the path's motions pass
 * through (a few percent of the mask for a typical path) and answers with
 * the same certificate, so a replan can stop the arm long before the whole
 * mask is ready. The mask is left partial: qrt_planner_plan and
 * qrt_planner_check_path refuse it (QRT_E_INVALID) until the next
 * qrt_planner_build_mask. Same return codes as qrt_planner_check_path. */
int qrt_planner_check_path_now(struct qrt_planner *pl,
                               const double (*waypoints_deg)[3], int n,
                               int *first_blocked);

#ifdef __cplusplus
}
#endif
#endif
