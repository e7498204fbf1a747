/* The planner: points in, a safe joint path out.
 *
 *   static struct qrt_planner pl;  // fixed size, caller-owned, no malloc
 *   struct qrt_params prm;  qrt_params_default(&prm);
 *   qrt_planner_init(&pl, &prm);                 // arm, margins, lattice
 *   qrt_planner_add_points(&pl, xyz, n);         // as often as needed
 *   qrt_planner_build_mask(&pl);                 // points -> C-space mask
 *   qrt_planner_plan(&pl, &start, &goal, &plan); // mask -> path
 *
 * Returns: every function that can fail returns an enum qrt_err, QRT_OK
 * (0) on success or a negative code; answers come back through
 * out-parameters. Functions that cannot fail return void or their answer.
 *
 * Terms (used by these headers and the core's sources):
 *   node        a point of the joint lattice, (ia, is, ie): one alpha,
 *               sigma and eta value each (qrtplan/lattice.h).
 *   cell box    a node plus or minus half a grid step (and the C-space
 *               margin) in every joint; a node is blocked when any
 *               configuration in its cell box collides.
 *   mask        one bit per node, set when the node is blocked.
 *   row         the mask bits of every eta node at one (alpha node, sigma
 *               node): the unit the conversion writes.
 *   whole mask  every row built for the points now in the table.
 *   partial mask  only the rows and nodes that calls have read so far,
 *               built as they were read (the _now and _straight calls).
 *   built as read  a row or node is computed the first time the search,
 *               a connection or a shortcut reads it, with the bit a whole
 *               mask gives it.
 *   single-node query  one node of a row not built yet, computed alone
 *               where the conversion's sector test allows it (the code
 *               says such a node is "asked").
 *   cluster     nearby points grouped so the conversion shares work
 *               among them; its bounding ball holds every member.
 *   disc        a point's or a bounding ball's trace in the arm's vertical
 *               plane at one alpha node: what link 3 must come near to
 *               touch it.
 *   view        what a cluster looks like at one alpha node (its disc, the
 *               sigma rows link 3 may reach), kept while the mask is
 *               partial.
 *   kept        retained from one call to the next for the same points,
 *               until the points change or the room is needed.
 *   straight motion  the linear joint motion between two configurations.
 *   connection  the straight motion between a start or goal configuration
 *               and a lattice node next to it.
 *   goal region the few nodes nearest the goal with their exact cost to
 *               it; its rim is its nodes with a free neighbour outside
 *               it, through which every path from outside enters.
 *   wrap        alpha's full circle: where it wraps, node n[0] is node 0
 *               again, and a move may cross from one to the other.
 *   proved free  shown collision-free by the mask walk (every node the
 *               motion's cell boxes cover is free) or by conservative
 *               advancement against the points themselves.
 *   exact points  the obstacle points as the caller gave them; the table
 *               holds them (to float rounding) while they fit, and past
 *               QRT_MAX_POINTS holds merged points instead: one entry a
 *               voxel, the box of its points, standing for every one of
 *               them (qrtplan/points.h).
 *   clearance   of a configuration: the least, over points and links (and
 *               the tool, when the arm has one), of the point's distance
 *               to the link's segment minus the link's radius and the
 *               workspace margin (metres); <= 0 means the
 *               configuration collides (docs/spec.md, the rule of
 *               section Collision).
 */
#ifndef QRTPLAN_PLANNER_H
#define QRTPLAN_PLANNER_H

#include <stddef.h>

#include "qrtplan/arm.h"
#include "qrtplan/config.h"
#include "qrtplan/lattice.h"
#include "qrtplan/params.h"
#include "qrtplan/planner_internal.h"
#include "qrtplan/points.h"
#include "qrtplan/status.h"

#ifdef __cplusplus
extern "C" {
#endif

/* QRT_TARGET_TOOL_TIP: a point for the tool tip (qrt_arm_tool_tip) to
 * reach, solved as the end-effector point of qrt_arm_tip_arm (its IK
 * branches are that arm's); the same as QRT_TARGET_XYZ without a tool. */
enum qrt_target_kind {
    QRT_TARGET_JOINTS = 0,
    QRT_TARGET_XYZ = 1,
    QRT_TARGET_TOOL_TIP = 2
};

/* Set every field: ik {QRT_FACING_ANY, QRT_ELBOW_ANY} (zeros) allows every
 * IK branch, and an xyz target's request outside the enums is refused. */
struct qrt_target {
    enum qrt_target_kind kind;
    double value[3]; /* joints in degrees, or a point in metres: the end
                        effector's (QRT_TARGET_XYZ) or the tool tip's */
    /* QRT_TARGET_XYZ and QRT_TARGET_TOOL_TIP only (ignored for joints):
     * the IK branches it may take (qrtplan/arm.h, qrt_ik_branch_check);
     * among those, the usual order (docs/spec.md section Planning) picks */
    struct qrt_ik_branch ik;
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
    /* the IK branch of start_deg and goal_deg for an xyz target (a side or
     * BOTH), {ANY, ANY} for a joints target or when unreachable */
    struct qrt_ik_branch start_ik, goal_ik;
    long start_node, goal_node; /* lattice nodes the path enters and leaves */
    long lattice_path_nodes;
    long nodes_expanded;
    /* nodes the sampled fallback's trees grew (0: it did not run) */
    long sampled_nodes;
    long cells_blocked; /* -1 when the whole mask was not built */
    long points, points_ignored, points_dropped;
    double voxel_m; /* 0 while points are exact */
    /* start_blocked and goal_blocked: end_free is 1 when the blocked end
     * was proved free and only its join to the lattice was not. Else
     * end_measured is 1 when the table holds the exact points, and
     * end_clearance_m is then the end's clearance (of its configurations,
     * the clearest; <= 0: every one collides, and only then does the
     * detail say so), or 0 under merged points: the core cannot tell a
     * collision from the merging's inflation, says neither, and a caller
     * holding the exact points measures them with qrt_planner_clearance
     * (docs/spec.md section Statuses). */
    int end_free, end_measured;
    double end_clearance_m;
    /* 0 until qrt_planner_certify_clearance sets it on an ok plan */
    double clearance_m;
};

/* clearance_m of a plan when no point is in the table. */
#define QRT_CLEARANCE_NONE_M 1e9

/* struct qrt_planner holds all state; its size is fixed at compile time by
 * qrtplan/config.h. Its fields are not API (qrtplan/planner_internal.h):
 * read the planner through these functions. */

/* Start with qrt_planner_init(pl, params): QRT_OK; QRT_E_ABI, with *pl
 * untouched, when the caller was compiled with other settings than the
 * library; QRT_E_INVALID for non-finite or negative margins, a bad arm or
 * a bad grid; QRT_E_TOO_BIG when the lattice exceeds this build. It is an
 * inline function, defined with the ABI guard at the end of this file. */

/* Forget every point (the arm and lattice stay). */
void qrt_planner_clear_points(struct qrt_planner *pl);

/* Add n points (3n doubles, metres, base frame); see points.h. */
int qrt_planner_add_points(struct qrt_planner *pl, const double *xyz, long n);

/* Convert the points into the whole C-space mask (paper blocks b-f). */
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

/* What the mask holds for the points now in the table: QRT_MASK_NONE
 * after init or when points changed, QRT_MASK_WHOLE after a whole build,
 * QRT_MASK_PARTIAL after the _now and _straight calls (their rows and
 * clusters are kept for the next such call). qrt_planner_plan and
 * qrt_planner_check_path need QRT_MASK_WHOLE. */
enum qrt_mask_state qrt_planner_mask_state(const struct qrt_planner *pl);

/* The mask itself, to read or write out; only the rows built so far are
 * meaningful unless qrt_planner_mask_state is QRT_MASK_WHOLE. */
const struct qrt_mask *qrt_planner_mask(const struct qrt_planner *pl);

/* Plan from start to goal on the whole mask (paper blocks g-h). With
 * shortcuts on (params.simplify), every plan first tries the straight
 * motion between the ends' first joints (the target's, or its allowed IK
 * solution nearest the other end) against the points themselves, in one
 * pass over them; when that proves it free, it is the plan. Returns QRT_OK
 * with the outcome in plan->status, or QRT_E_LIMITS when joints are
 * outside the limits, QRT_E_INVALID for NaN/Inf, an xyz target's ik that
 * is not a request, or a mask that is not whole. */
int qrt_planner_plan(struct qrt_planner *pl, const struct qrt_target *start,
                     const struct qrt_target *goal, struct qrt_plan *plan);

/* qrt_planner_build_mask and qrt_planner_plan in one, with less work: the
 * plan is the same (the same waypoints, cost and nodes expanded). A
 * straight motion proved against the points needs no mask node at all;
 * otherwise only the nodes the plan reads are built as read: by
 * single-node queries where the sector test holds (every grid under 90
 * degrees), else a row at a time. plan->cells_blocked is -1 unless the
 * whole mask got built, and the mask is left partial: a later
 * qrt_planner_plan or qrt_planner_check_path needs qrt_planner_build_mask
 * first. Same return codes as qrt_planner_plan, without the mask's.
 *
 * The nodes and rows it builds, and those qrt_planner_check_path_now and
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
 * are built only if the first test fails). QRT_OK with *straight 1 and
 * *plan the straight motion (status ok, cells_blocked -1), or *straight 0:
 * call qrt_planner_build_mask and qrt_planner_plan (also for xyz targets,
 * simplification off, or points lost to capacity); QRT_E_INVALID /
 * QRT_E_LIMITS for bad targets (*straight 0). The mask is left partial
 * either way. */
int qrt_planner_plan_straight(struct qrt_planner *pl,
                              const struct qrt_target *start,
                              const struct qrt_target *goal,
                              struct qrt_plan *plan, int *straight);

/* Is a path still safe on the whole mask (a replan's question about the
 * path being executed)? *first_blocked is the index of the first segment
 * (waypoint i to i+1) that cannot be proved free, or -1 if every segment is
 * (same certificate as the planner's own motions: the mask walk, else
 * conservative advancement against the points); 0 when points were lost
 * to capacity, since then nothing can be proved. QRT_E_INVALID for a mask
 * that is not whole, n < 1 or NaN/Inf; QRT_E_LIMITS for a waypoint outside
 * the limits. */
int qrt_planner_check_path(const struct qrt_planner *pl,
                           const double (*waypoints_deg)[3], int n,
                           int *first_blocked);

/* The same question asked of the points now in the table, before any mask
 * is built for them: builds only the mask rows the path's motions pass
 * through and answers with the same certificate, so a replan can stop the
 * arm long before the whole mask is ready. A segment that needs
 * advancement (a sampled path, a join to the lattice) puts the table in
 * Morton order first, as the certificate does, so that far blocks are
 * passed over whole; the answer is the same. The mask is left partial:
 * qrt_planner_plan and qrt_planner_check_path refuse it (QRT_E_INVALID)
 * until the next qrt_planner_build_mask. Same return codes as
 * qrt_planner_check_path, without the mask's. */
int qrt_planner_check_path_now(struct qrt_planner *pl,
                               const double (*waypoints_deg)[3], int n,
                               int *first_blocked);

/* Certify an ok plan's clearance, in plan->clearance_m: a lower bound on
 * the least distance over its whole motion between the arm's own capsules
 * (links and tool at their radii, the margin not subtracted) and the
 * points given, at least the margin (the path's proof gives that much),
 * within 4 mm of the true least distance where the points are exact and
 * the nearest is in reach (docs/spec.md section Guarantee, Clearance);
 * QRT_CLEARANCE_NONE_M when no point was given. Call it with the table the
 * plan was made on. A separate call because it costs more than a small
 * plan: a pass over the points for every sample of the motion.
 * QRT_E_INVALID (plan untouched) for a plan that is not ok. */
int qrt_planner_certify_clearance(struct qrt_planner *pl,
                                  struct qrt_plan *plan);

/* The clearance of the arm at joints q_deg from the n points xyz (3n
 * doubles, metres, base frame), with this planner's arm and margin_m: the
 * exact check of the rule of docs/spec.md section Collision, for a caller
 * that holds the exact points (they may be passed in parts; the least of
 * the parts' answers is the whole's). A pure function of those: it
 * neither reads nor changes the point table. 1e30 when n is 0. */
double qrt_planner_clearance(const struct qrt_planner *pl,
                             const double q_deg[3], const double *xyz, long n);

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
    long target_bytes;  /* sizeof(struct qrt_target) */
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
    abi.target_bytes = (long)sizeof(struct qrt_target);
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

#ifdef __cplusplus
}
#endif
#endif
