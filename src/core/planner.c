/* The planner: targets to joints, connections to the lattice, search,
 * and path simplification (paper blocks g and h). */
#include "qrtplan/planner.h"

#include <math.h>
#include <stddef.h>

#include "clearance.h"
#include "cluster.h"
#include "geom.h"
#include "lazy.h"
#include "motion.h"
#include "order.h"
#include "raster.h"
#include "sampled.h"
#include "search.h"
#include "sweep.h"
#include "tuning.h"

void qrt_params_default(struct qrt_params *params)
{
    qrt_arm_default(&params->arm);
    params->margin_m = 0.01;
    params->cspace_margin_deg = 0.0;
    params->grid_deg = 5.0;
    params->use_astar = 1;
    params->simplify = 1;
    params->sample_draws = QRT_SAMPLE_DRAWS_DEFAULT;
}

static void copy_joints(double dst[3], const double src[3])
{
    dst[0] = src[0];
    dst[1] = src[1];
    dst[2] = src[2];
}

int qrt_planner_init_abi(struct qrt_planner *pl,
                         const struct qrt_params *params,
                         const struct qrt_abi *caller)
{
    const struct qrt_arm *arm = &params->arm;
    int rc;
    /* First, before *pl is touched: a caller compiled with other settings
     * has a struct qrt_planner of another size and layout, and writing this
     * library's into it would run past its end (planner.h, struct
     * qrt_abi). */
    if (qrt_abi_check(caller, NULL, 0) != QRT_OK)
        return QRT_E_ABI;
    if (qrt_arm_validate(arm) != QRT_OK)
        return QRT_E_INVALID;
    if (!isfinite(params->margin_m) || params->margin_m < 0.0 ||
        params->margin_m > 10.0)
        return QRT_E_INVALID;
    if (!isfinite(params->cspace_margin_deg) ||
        params->cspace_margin_deg < 0.0 || params->cspace_margin_deg > 45.0)
        return QRT_E_INVALID;
    if (params->sample_draws < 0 || params->sample_draws > QRT_SAMPLE_DRAWS_MAX)
        return QRT_E_INVALID;
    rc = qrt_lattice_init(&pl->mask.lat, arm, params->grid_deg);
    if (rc != QRT_OK)
        return rc;
    pl->params = *params;
    qrt_arm_collision_arm(arm, &pl->collision_arm);
    /* the tool's reach too: a point only the tool can touch is kept */
    qrt_points_reset(&pl->points, qrt_arm_reach_m(arm) + params->margin_m);
    pl->mask_state = QRT_MASK_NONE;
    pl->points_ordered = 0;
    pl->cells_blocked = 0;
    pl->lazy_clusters = 0;
    pl->lazy_raster = NULL;
    return QRT_OK;
}

void qrt_planner_clear_points(struct qrt_planner *pl)
{
    qrt_points_reset(&pl->points, pl->points.reach_m);
    pl->mask_state = QRT_MASK_NONE;
    pl->points_ordered = 0;
}

int qrt_planner_add_points(struct qrt_planner *pl, const double *xyz, long n)
{
    int rc = qrt_points_add(&pl->points, xyz, n);
    /* points added: no mask is theirs yet; refused points leave a whole
     * mask whole, but the kept clusters are given up all the same */
    if (n > 0 && (rc == QRT_OK || pl->mask_state != QRT_MASK_WHOLE))
        pl->mask_state = QRT_MASK_NONE;
    if (n > 0)
        pl->points_ordered = 0;
    return rc;
}

/* The table in Morton order (order.h), for the checks that pass over far
 * blocks of it (the certificate, the sampled fallback): once per change of
 * the points, the kept clusters renumbered. Ordering costs more than a
 * plan's own passes over the points save, so a plan does not order the
 * table first. Where the scratch is too small the order stays as it came,
 * which changes no answer. */
static void order_points(struct qrt_planner *pl)
{
    /* the clustering's scratch of parts 0 and 1 (raster_part), idle once
     * the search is over */
    int32_t *a = pl->heap_pos, *b = pl->search.cluster_scratch;
    long room = QRT_MAX_NODES;
    if (QRTI_OWN_CLUSTER_SCRATCH > 1) {
        a = pl->cluster_scratch[0];
        b = pl->cluster_scratch[1];
        room = QRTI_OWN_CLUSTER_SCRATCH;
    }
    if (pl->points_ordered)
        return;
    pl->points_ordered = 1;
    if (qrt_points_order_scratch_len(pl->points.count) > room)
        return;
    qrt_points_order(&pl->points, a, b);
    qrt_lazy_renumber(pl, a);
}

struct cluster_ctx {
    const struct qrt_raster *raster;
    struct qrt_point_axes ax;
};

static void raster_cluster(void *ctx, const int32_t *members, int m)
{
    const struct cluster_ctx *c = (const struct cluster_ctx *)ctx;
    qrt_raster_cluster(c->raster, &c->ax, members, m);
}

/* Link k's collision radius (the collision arm's) for the points now in
 * the table. */
static double points_radius(const struct qrt_planner *pl, int k)
{
    return pl->collision_arm.link_radius_m[k] + pl->params.margin_m +
           qrt_points_inflation_m(&pl->points);
}

/* Collision radii for the points now in the table, and an empty mask. */
static void start_mask(struct qrt_planner *pl)
{
    int k, ia, is, w;
    for (k = 0; k < 3; k++)
        pl->radius_m[k] = points_radius(pl, k);
    for (ia = 0; ia < QRT_MAX_NA; ia++)
        for (is = 0; is < QRT_MAX_NS; is++)
            for (w = 0; w < QRT_ROW_WORDS; w++)
                pl->mask.rows[ia][is][w] = 0;
    pl->mask_state = QRT_MASK_NONE; /* until rows are built */
}

int qrt_planner_build_mask_begin(struct qrt_planner *pl)
{
    start_mask(pl);
    return QRT_OK;
}

/* Raster part `part` of `nparts` (rows: NULL, or only those rows). */
static void raster_part(struct qrt_planner *pl, int part, int nparts,
                        const uint64_t *rows)
{
    struct qrt_raster r;
    int32_t *scratch;
    long i;
    qrt_raster_setup(&r, &pl->mask, &pl->collision_arm, pl->radius_m,
                     pl->params.cspace_margin_deg, part, nparts);
    if (rows)
        qrt_raster_only_rows(&r, rows);
    /* the search's node arrays are idle until the next search: each part
     * lends its own for the clustering, unless the table is too large for
     * them and the planner has scratch of its own (planner_internal.h) */
    scratch = part == 0 ? pl->heap_pos : pl->search.cluster_scratch;
    if (QRTI_OWN_CLUSTER_SCRATCH > 1)
        scratch = pl->cluster_scratch[part];
    if (qrt_cluster_scratch_len(pl->points.count) <=
        (QRTI_OWN_CLUSTER_SCRATCH > 1 ? QRTI_OWN_CLUSTER_SCRATCH
                                      : QRT_MAX_NODES)) {
        struct cluster_ctx ctx;
        double cell;
        ctx.raster = &r;
        ctx.ax = qrt_points_axes(&pl->points);
        cell = qrt_cluster_cell_for(
            pl->points.count,
            qrt_cluster_count(&ctx.ax, pl->points.count, QRT_CLUSTER_CELL_M,
                              QRT_CLUSTER_MAX, scratch));
        qrt_cluster_points(&ctx.ax, pl->points.count, cell, QRT_CLUSTER_MAX,
                           scratch, raster_cluster, &ctx);
    } else {
        struct qrt_point_axes ax = qrt_points_axes(&pl->points);
        for (i = 0; i < pl->points.count; i++) {
            double p[3];
            qrt_point_at(&ax, i, p);
            qrt_raster_point(&r, p);
        }
    }
}

int qrt_planner_build_mask_part(struct qrt_planner *pl, int part, int nparts)
{
    if (nparts < 1 || nparts > QRT_MAX_MASK_PARTS || part < 0 || part >= nparts)
        return QRT_E_INVALID;
    raster_part(pl, part, nparts, NULL);
    return QRT_OK;
}

int qrt_planner_build_mask_end(struct qrt_planner *pl)
{
    pl->cells_blocked = qrt_mask_count_blocked(&pl->mask);
    pl->mask_state = QRT_MASK_WHOLE;
    return QRT_OK;
}

enum qrt_mask_state qrt_planner_mask_state(const struct qrt_planner *pl)
{
    return pl->mask_state;
}

const struct qrt_mask *qrt_planner_mask(const struct qrt_planner *pl)
{
    return &pl->mask;
}

int qrt_planner_build_mask(struct qrt_planner *pl)
{
    qrt_planner_build_mask_begin(pl);
    qrt_planner_build_mask_part(pl, 0, 1);
    return qrt_planner_build_mask_end(pl);
}

/* What checks against the raw points add to every radius: the C-space
 * margin (Eq. 12) becomes the distance any arm point can move when every
 * joint turns by that margin. */
static double cspace_shift_m(const struct qrt_planner *pl)
{
    const double *l = pl->collision_arm.link_m; /* the tool's length too */
    return pl->params.cspace_margin_deg * QRT_DEG *
           ((l[0] + l[1] + l[2]) + (l[1] + l[2]) + l[2]);
}

/* Collision radii for checks against the points now in the table: the
 * mask's radii for them (the same sums, so the same values wherever a mask
 * is built or being built for these points) plus the C-space shift; known
 * before any mask is. */
static void exact_radii(const struct qrt_planner *pl, double radius[3])
{
    double shift = cspace_shift_m(pl);
    int k;
    for (k = 0; k < 3; k++)
        radius[k] = points_radius(pl, k) + shift;
}

static int node_blocked(void *ctx, const int ijk[3])
{
    return qrt_lazy_node_blocked((struct qrt_planner *)ctx, ijk);
}

/* The mask's proof of a straight motion, on rows built as they are read
 * while qrt_planner_plan_now runs. */
static int motion_free(struct qrt_planner *pl, const double a[3],
                       const double b[3])
{
    if (qrt_lazy_building(pl))
        return qrt_motion_free_asking(&pl->mask, node_blocked, pl, a, b);
    return qrt_motion_free_on_mask(&pl->mask, a, b);
}

/* Add node ijk (if inside the lattice, free, new, and reachable from q by
 * a motion proved safe) to ends. */
static void try_end(struct qrt_planner *pl, const double q[3], int ijk[3],
                    const double radius[3], struct qrt_ends *ends)
{
    const struct qrt_lattice *lat = &pl->mask.lat;
    double node_deg[3];
    long node;
    int j;
    if (ends->count >= QRT_MAX_ENDS)
        return;
    if (lat->alpha_wraps)
        ijk[0] = ((ijk[0] % lat->n[0]) + lat->n[0]) % lat->n[0];
    for (j = 0; j < 3; j++)
        if (ijk[j] < 0 || ijk[j] >= lat->n[j])
            return;
    if (qrt_lazy_node_blocked(pl, ijk))
        return;
    node = qrt_lattice_index(lat, ijk);
    for (j = 0; j < ends->count; j++)
        if (ends->node[j] == node)
            return;
    qrt_lattice_joints(lat, ijk, node_deg);
    if (!motion_free(pl, q, node_deg) &&
        !qrt_motion_free_exact(&pl->collision_arm, radius, &pl->points, NULL,
                               lat, q, node_deg, QRT_EXACT_MAX_STEPS,
                               QRT_WITNESS_AFTER))
        return;
    ends->node[ends->count] = node;
    ends->cost[ends->count] =
        qrt_arm_joint_distance(&pl->params.arm, q, node_deg);
    ends->count++;
}

/* A start or goal is connected to nodes up to QRT_CONNECT_SHELLS cells
 * away from its nearest node: past the 26 neighbours, the next shells are
 * tried, each only when the one inside it gave nothing (and, as in the
 * first, the first node that connects is taken). The cells are
 * conservative, so near a surface many are blocked, and a free end amid
 * them is otherwise stranded. */

/* Lattice nodes that q can be connected to: the corners of the grid cell
 * holding q, or, when none of those is free and reachable (q close to an
 * obstacle), the nodes around its nearest node, shell by shell. */
static void collect_ends(struct qrt_planner *pl, const double q[3],
                         struct qrt_ends *ends)
{
    const struct qrt_lattice *lat = &pl->mask.lat;
    double radius[3], x[3];
    int lo[3], near[3], j, c, shell;
    exact_radii(pl, radius);
    ends->count = 0;
    for (j = 0; j < 3; j++) {
        x[j] = (q[j] - lat->lo_deg[j]) / lat->grid_deg;
        lo[j] = (int)floor(x[j]);
        near[j] = (int)floor(x[j] + 0.5);
    }
    for (c = 0; c < 8; c++) {
        int ijk[3];
        for (j = 0; j < 3; j++)
            ijk[j] = lo[j] + ((c >> j) & 1);
        /* a corner q sits on needs no second copy one cell further */
        if ((c & 1 && x[0] == lo[0]) || (c & 2 && x[1] == lo[1]) ||
            (c & 4 && x[2] == lo[2]))
            continue;
        try_end(pl, q, ijk, radius, ends);
    }
    for (shell = 1; shell <= QRT_CONNECT_SHELLS && ends->count == 0; shell++) {
        int side = 2 * shell + 1, cube = side * side * side;
        for (c = 0; c < cube && ends->count == 0; c++) {
            int d[3], ijk[3];
            d[0] = c / (side * side) - shell;
            d[1] = (c / side) % side - shell;
            d[2] = c % side - shell;
            if (d[0] * d[0] < shell * shell && d[1] * d[1] < shell * shell &&
                d[2] * d[2] < shell * shell)
                continue; /* inside: an earlier shell */
            for (j = 0; j < 3; j++)
                ijk[j] = near[j] + d[j];
            try_end(pl, q, ijk, radius, ends);
        }
    }
}

/* END_COLLIDES only where the exact points collide; END_UNPROVEN where
 * the end is not proved free and no collision is shown: merged points, or
 * exact ones within the inflation of rounding and the C-space margin. */
enum end_outcome {
    END_OK,
    END_UNREACHABLE,
    END_COLLIDES,
    END_UNPROVEN,
    END_STRANDED
};

/* The clearance of q by the rule itself (the links' and the tool's own
 * capsules, not the collision arm's), from the table's exact points (the
 * caller checks that they are exact): each radius less the float rounding
 * of the stored points, so that a value <= 0 is a collision of the points
 * as given; the rounding added back, so the value is theirs to within
 * it. */
static double exact_clearance(const struct qrt_planner *pl, const double q[3])
{
    double p[QRT_CHAIN_MAX + 1][3], radius[QRT_CHAIN_MAX],
        rounding = qrt_points_inflation_m(&pl->points);
    int n = qrt_arm_capsules(&pl->params.arm, q, pl->params.margin_m - rounding,
                             p, radius);
    return qrt_chain_clearance_capped((const double(*)[3])p, radius, n,
                                      &pl->points, NULL, 1e30) -
           rounding;
}

/* The joints a start or goal may take, nearest to ref first, with the IK
 * branch of each in branch_of: the target's own for joints ({ANY, ANY}),
 * for an end-effector point (or a tool tip's, solved on the tip arm) every
 * IK solution of a branch the target allows. Returns how many (0: none
 * inside the reach, limits and branch). */
static int end_joints(const struct qrt_planner *pl, const struct qrt_target *t,
                      const double ref[3], double out[4][3],
                      struct qrt_ik_branch branch_of[4])
{
    double sols[4][3], dist[4];
    struct qrt_ik_branch found[4];
    int order[4] = {0, 1, 2, 3}, n, all, i;
    if (t->kind == QRT_TARGET_JOINTS) {
        copy_joints(out[0], t->value);
        branch_of[0].facing = QRT_FACING_ANY;
        branch_of[0].elbow = QRT_ELBOW_ANY;
        return 1;
    }
    if (t->kind == QRT_TARGET_TOOL_TIP) {
        struct qrt_arm tip_arm;
        qrt_arm_tip_arm(&pl->params.arm, &tip_arm);
        all = qrt_arm_ik_branches(&tip_arm, t->value, ref[0], sols, found);
    } else {
        all =
            qrt_arm_ik_branches(&pl->params.arm, t->value, ref[0], sols, found);
    }
    /* the branches not asked for are dropped before today's order picks */
    n = 0;
    for (i = 0; i < all; i++) {
        if (!qrt_ik_branch_allows(&t->ik, &found[i]))
            continue;
        copy_joints(sols[n], sols[i]);
        found[n] = found[i];
        n++;
    }
    for (i = 0; i < n; i++) {
        order[i] = i;
        dist[i] = qrt_arm_joint_distance(&pl->params.arm, ref, sols[i]);
    }
    for (i = 1; i < n; i++) { /* insertion sort: n <= 4 */
        int o = order[i], m = i;
        while (m > 0 && dist[order[m - 1]] > dist[o]) {
            order[m] = order[m - 1];
            m--;
        }
        order[m] = o;
    }
    for (i = 0; i < n; i++) {
        copy_joints(out[i], sols[order[i]]);
        branch_of[i] = found[order[i]];
    }
    return n;
}

/* Turn a start or goal into joints, the IK branch they belong to, and
 * their lattice connections. For an end-effector point every allowed IK
 * solution is tried, nearest to ref first. When no solution is proved free
 * and the points are exact, *clear_m is the clearest solution's exact
 * clearance and *measured 1 (else 0). */
static enum end_outcome
resolve_end(struct qrt_planner *pl, const struct qrt_target *t,
            const double ref[3], double q[3], struct qrt_ik_branch *branch,
            struct qrt_ends *ends, int *measured, double *clear_m)
{
    double sols[4][3], radius[3];
    struct qrt_ik_branch branch_of[4];
    int n, i, first_free = -1;
    *measured = 0;
    *clear_m = 0.0;
    exact_radii(pl, radius);
    n = end_joints(pl, t, ref, sols, branch_of);
    if (n == 0)
        return END_UNREACHABLE;
    for (i = 0; i < n; i++) {
        const double *s = sols[i];
        /* a free cell proves s free; only near obstacles measure it */
        if (!motion_free(pl, s, s) &&
            qrt_clearance(&pl->collision_arm, radius, &pl->points, s) <= 0.0)
            continue;
        if (first_free < 0)
            first_free = i;
        collect_ends(pl, s, ends);
        if (ends->count > 0) {
            copy_joints(q, s);
            *branch = branch_of[i];
            return END_OK;
        }
    }
    /* stranded: the first free solution, which the sampled fallback may
     * still join to the other end */
    copy_joints(q, sols[first_free >= 0 ? first_free : 0]);
    *branch = branch_of[first_free >= 0 ? first_free : 0];
    if (first_free >= 0)
        return END_STRANDED;
    if (pl->points.voxel_m > 0.0)
        return END_UNPROVEN; /* merged: a collision cannot be told */
    *measured = 1;
    *clear_m = exact_clearance(pl, sols[0]);
    for (i = 1; i < n; i++) {
        double c = exact_clearance(pl, sols[i]);
        if (c > *clear_m)
            *clear_m = c;
    }
    return *clear_m <= 0.0 ? END_COLLIDES : END_UNPROVEN;
}

static int check_target(const struct qrt_arm *arm, const struct qrt_target *t)
{
    int k;
    if (t->kind != QRT_TARGET_JOINTS && t->kind != QRT_TARGET_XYZ &&
        t->kind != QRT_TARGET_TOOL_TIP)
        return QRT_E_INVALID;
    for (k = 0; k < 3; k++)
        if (!isfinite(t->value[k]))
            return QRT_E_INVALID;
    if (t->kind == QRT_TARGET_JOINTS)
        return qrt_arm_check_joints(arm, t->value);
    return qrt_ik_branch_check(&t->ik);
}

/* Both targets of a plan: QRT_OK, or the first one's error. */
static int check_targets(const struct qrt_planner *pl,
                         const struct qrt_target *start,
                         const struct qrt_target *goal)
{
    int rc = check_target(&pl->params.arm, start);
    return rc != QRT_OK ? rc : check_target(&pl->params.arm, goal);
}

static void set_status(struct qrt_plan *plan, enum qrt_plan_status status,
                       const char *detail)
{
    plan->status = status;
    plan->detail = detail;
}

/* Waypoint i of the unsimplified route: start, lattice nodes, goal. */
static void route_point(const struct qrt_planner *pl, const double s[3],
                        const double g[3], long len, long i, double out[3])
{
    int ijk[3];
    if (i > 0 && i <= len) {
        qrt_lattice_coords(&pl->mask.lat, pl->open.heap[i - 1].node, ijk);
        qrt_lattice_joints(&pl->mask.lat, ijk, out);
        return;
    }
    copy_joints(out, i == 0 ? s : g);
}

/* Append w to the plan, merging it with a coincident last waypoint (the
 * later one wins, so the goal is kept exactly as given). */
static int append_waypoint(const struct qrt_planner *pl, struct qrt_plan *plan,
                           const double w[3], int is_last)
{
    int n = plan->n_waypoints;
    if (n > 0 && qrt_arm_joint_distance(&pl->params.arm,
                                        plan->waypoints_deg[n - 1], w) < 1e-9) {
        if (n == 1 && !is_last)
            return 1;
        if (n > 1)
            n--;
    }
    if (n >= QRT_MAX_WAYPOINTS)
        return 0;
    copy_joints(plan->waypoints_deg[n], w);
    plan->n_waypoints = n + 1;
    return 1;
}

/* Greedy string pulling: from each kept waypoint jump to the farthest
 * later one that the mask proves reachable in a straight motion. The next
 * route point is always reachable (a lattice edge or a proved connection). */
static int emit_route(struct qrt_planner *pl, const double s[3],
                      const double g[3], long len, struct qrt_plan *plan)
{
    long last = len + 1, anchor = 0, j;
    double a[3], w[3];
    plan->n_waypoints = 0;
    route_point(pl, s, g, len, 0, a);
    append_waypoint(pl, plan, a, 0);
    while (anchor < last) {
        long next = anchor + 1;
        if (pl->params.simplify)
            for (j = anchor + 2; j <= last; j++) {
                route_point(pl, s, g, len, j, w);
                if (!motion_free(pl, a, w))
                    break;
                next = j;
            }
        route_point(pl, s, g, len, next, a);
        if (!append_waypoint(pl, plan, a, next == last))
            return 0;
        anchor = next;
    }
    return 1;
}

static double route_length(const struct qrt_planner *pl, const double s[3],
                           const double g[3], long len)
{
    double a[3], b[3], total = 0.0;
    long i;
    route_point(pl, s, g, len, 0, a);
    for (i = 1; i <= len + 1; i++) {
        route_point(pl, s, g, len, i, b);
        total += qrt_arm_joint_distance(&pl->params.arm, a, b);
        copy_joints(a, b);
    }
    return total;
}

static double route_cost(const struct qrt_planner *pl,
                         const struct qrt_plan *plan)
{
    double cost = 0.0;
    int i;
    for (i = 1; i < plan->n_waypoints; i++)
        cost +=
            qrt_arm_joint_distance(&pl->params.arm, plan->waypoints_deg[i - 1],
                                   plan->waypoints_deg[i]);
    return cost;
}

/* The plan of a straight motion from a to b that has been proved free. */
static void set_straight_plan(const struct qrt_planner *pl,
                              struct qrt_plan *plan, const double a[3],
                              const double b[3])
{
    plan->n_waypoints = 0;
    append_waypoint(pl, plan, a, 0);
    append_waypoint(pl, plan, b, 1);
    plan->cost_deg = plan->lattice_cost_deg = route_cost(pl, plan);
    set_status(plan, QRT_STATUS_OK, "straight motion is free");
}

/* The sampled fallback (sampled.h) where the lattice has no path: 1 when
 * it decided the plan (a path, or a path too long for the plan table),
 * 0 when it found none. The path is pulled taut like a lattice route
 * (emit_route), each shortcut proved the way the edges were. */
static int sampled_plan(struct qrt_planner *pl, const double qs[3],
                        const double qg[3], struct qrt_plan *plan)
{
    struct qrt_sampled_space sp;
    const struct qrti_sampled_node *node = pl->search.sampled.node;
    const int32_t *path = pl->search.sampled.path;
    int32_t n, anchor = 0, i;
    double raw = 0.0;
    if (pl->params.sample_draws <= 0)
        return 0;
    order_points(pl);
    sp.arm = &pl->collision_arm;
    exact_radii(pl, sp.radius_m);
    sp.pts = &pl->points;
    qrt_points_block_boxes(&pl->points, pl->search.sampled.block_box);
    sp.block_box = (const float(*)[6])pl->search.sampled.block_box;
    sp.lat = &pl->mask.lat;
    sp.node = pl->search.sampled.node;
    sp.path = pl->search.sampled.path;
    sp.max_nodes = QRTI_SAMPLED_NODES;
    n = qrt_sampled_connect(&sp, qs, qg, pl->params.sample_draws,
                            &plan->sampled_nodes);
    if (n < 2)
        return 0;
    for (i = 1; i < n; i++)
        raw += qrt_arm_joint_distance(&pl->params.arm, node[path[i - 1]].q_deg,
                                      node[path[i]].q_deg);
    plan->n_waypoints = 0;
    append_waypoint(pl, plan, node[path[0]].q_deg, 0);
    while (anchor < n - 1) {
        int32_t next = anchor + 1, j;
        if (pl->params.simplify)
            for (j = anchor + 2; j < n; j++) {
                if (!qrt_sampled_motion_free(&sp, node[path[anchor]].q_deg,
                                             node[path[j]].q_deg))
                    break;
                next = j;
            }
        if (!append_waypoint(pl, plan, node[path[next]].q_deg, next == n - 1)) {
            plan->n_waypoints = 0;
            set_status(plan, QRT_STATUS_CAPACITY,
                       "the path has more waypoints than the plan table "
                       "holds");
            return 1;
        }
        anchor = next;
    }
    plan->lattice_cost_deg = raw;
    plan->cost_deg = route_cost(pl, plan);
    set_status(plan, QRT_STATUS_OK,
               "path found by sampling (none through the lattice)");
    return 1;
}

static void reset_plan(const struct qrt_planner *pl, struct qrt_plan *plan)
{
    int k;
    plan->status = QRT_STATUS_NO_PATH;
    plan->detail = "";
    plan->n_waypoints = 0;
    plan->cost_deg = 0.0;
    plan->lattice_cost_deg = 0.0;
    for (k = 0; k < 3; k++)
        plan->start_deg[k] = plan->goal_deg[k] = 0.0;
    plan->start_ik.facing = plan->goal_ik.facing = QRT_FACING_ANY;
    plan->start_ik.elbow = plan->goal_ik.elbow = QRT_ELBOW_ANY;
    plan->start_node = plan->goal_node = -1;
    plan->lattice_path_nodes = 0;
    plan->nodes_expanded = 0;
    plan->sampled_nodes = 0;
    plan->cells_blocked = pl->cells_blocked;
    plan->points = pl->points.count;
    plan->points_ignored = pl->points.ignored_far;
    plan->points_dropped = pl->points.dropped;
    plan->voxel_m = pl->points.voxel_m;
    plan->end_free = plan->end_measured = 0;
    plan->end_clearance_m = 0.0;
    plan->clearance_m = 0.0;
}

/* The sentence pre BRANCH post, BRANCH naming the IK branch that *ik (a
 * request other than {ANY, ANY}) asks for: literals only, since the core
 * keeps no tables of pointers (tests/check_core_symbols.sh). */
/* clang-format off */
#define BRANCH_SENTENCE(ik, pre, post)                                         \
    ((ik)->facing == QRT_FACING_FRONT                                          \
         ? ((ik)->elbow == QRT_ELBOW_UP                                        \
                ? pre " facing front with the elbow up" post                   \
            : (ik)->elbow == QRT_ELBOW_DOWN                                    \
                ? pre " facing front with the elbow down" post                 \
                : pre " facing front" post)                                    \
     : (ik)->facing == QRT_FACING_BACK                                         \
         ? ((ik)->elbow == QRT_ELBOW_UP                                        \
                ? pre " facing back with the elbow up" post                    \
            : (ik)->elbow == QRT_ELBOW_DOWN                                    \
                ? pre " facing back with the elbow down" post                  \
                : pre " facing back" post)                                     \
     : (ik)->elbow == QRT_ELBOW_UP ? pre " with the elbow up" post             \
                                   : pre " with the elbow down" post)
/* clang-format on */

/* end_detail for a target that asks for an IK branch. */
static const char *branch_detail(enum end_outcome o, int is_goal,
                                 const struct qrt_ik_branch *ik)
{
    switch (o) {
    case END_UNREACHABLE:
        return is_goal ? BRANCH_SENTENCE(ik, "goal point has no IK solution",
                                         " inside the arm's reach and limits")
                       : BRANCH_SENTENCE(ik, "start point has no IK solution",
                                         " inside the arm's reach and limits");
    case END_COLLIDES:
        return is_goal ? BRANCH_SENTENCE(ik, "every goal configuration",
                                         " collides with obstacle points")
                       : BRANCH_SENTENCE(ik, "every start configuration",
                                         " collides with obstacle points");
    case END_STRANDED:
        return is_goal ? BRANCH_SENTENCE(ik, "goal",
                                         " is free but no move to it from the "
                                         "lattice can be proved safe")
                       : BRANCH_SENTENCE(ik, "start",
                                         " is free but no move from it to the "
                                         "lattice can be proved safe");
    /* END_UNPROVEN keeps end_detail's sentence: a host that measures the
     * end names the branch (src/cli/end_check.c), and literals for every
     * branch would cost the board's flash */
    case END_UNPROVEN:
    case END_OK:
        break;
    }
    return "";
}

/* The detail of an end that failed; for a target that asks for an IK
 * branch, the sentence names that branch. merged: the table holds merged
 * points (END_UNPROVEN cannot say whether the end is clear); tool: the arm
 * has one, whose collision capsule (qrt_arm_collision_arm) is wider than
 * the rule's. */
static const char *end_detail(enum end_outcome o, int is_goal,
                              const struct qrt_target *t, int merged, int tool)
{
    if (o != END_OK && o != END_UNPROVEN && t->kind != QRT_TARGET_JOINTS &&
        (t->ik.facing != QRT_FACING_ANY || t->ik.elbow != QRT_ELBOW_ANY))
        return branch_detail(o, is_goal, &t->ik);
    switch (o) {
    case END_UNREACHABLE:
        return is_goal ? "goal point is outside the arm's reach or limits"
                       : "start point is outside the arm's reach or limits";
    case END_COLLIDES:
        return is_goal ? "goal configuration collides with obstacle points"
                       : "start configuration collides with obstacle points";
    case END_UNPROVEN:
        if (merged)
            return is_goal ? "goal cannot be proved free under point "
                             "merging; only the exact points can tell "
                             "whether it collides"
                           : "start cannot be proved free under point "
                             "merging; only the exact points can tell "
                             "whether it collides";
        if (tool)
            return is_goal ? "goal is clear of the points, but not by the "
                             "C-space margin, rounding and tool capsule the "
                             "planner adds, so cannot be proved free"
                           : "start is clear of the points, but not by the "
                             "C-space margin, rounding and tool capsule the "
                             "planner adds, so cannot be proved free";
        return is_goal ? "goal is clear of the points, but not by the "
                         "C-space margin and rounding the planner adds, so "
                         "cannot be proved free"
                       : "start is clear of the points, but not by the "
                         "C-space margin and rounding the planner adds, so "
                         "cannot be proved free";
    case END_STRANDED:
        return is_goal ? "goal is free but no move to it from the lattice "
                         "can be proved safe"
                       : "start is free but no move from it to the lattice "
                         "can be proved safe";
    case END_OK:
        break;
    }
    return "";
}

static enum qrt_plan_status end_status(enum end_outcome o, int is_goal)
{
    if (o == END_UNREACHABLE)
        return QRT_STATUS_UNREACHABLE;
    return is_goal ? QRT_STATUS_GOAL_BLOCKED : QRT_STATUS_START_BLOCKED;
}

/* Open space, before any mask: the straight motion between the ends'
 * first joints (as resolve_end orders them) proved free against the points
 * themselves, in one pass over them. 1 with *plan that motion; 0 when it
 * is not proved, and the mask decides (the plan is then untouched). The
 * same test comes first in every plan, so plans with and without a whole
 * mask agree. */
static int plan_swept(struct qrt_planner *pl, const struct qrt_target *start,
                      const struct qrt_target *goal, struct qrt_plan *plan)
{
    static const double origin[3] = {0.0, 0.0, 0.0};
    double qs[4][3], qg[4][3], radius[3];
    struct qrt_ik_branch bs[4], bg[4];
    if (!pl->params.simplify || pl->points.dropped > 0)
        return 0;
    if (end_joints(pl, start,
                   goal->kind == QRT_TARGET_JOINTS ? goal->value : origin, qs,
                   bs) == 0 ||
        end_joints(pl, goal, qs[0], qg, bg) == 0)
        return 0;
    exact_radii(pl, radius);
    if (!qrt_sweep_free(&pl->collision_arm, radius, &pl->points, &pl->mask.lat,
                        qs[0], qg[0], pl->search.sweep))
        return 0;
    reset_plan(pl, plan);
    copy_joints(plan->start_deg, qs[0]);
    copy_joints(plan->goal_deg, qg[0]);
    plan->start_ik = bs[0];
    plan->goal_ik = bg[0];
    set_straight_plan(pl, plan, qs[0], qg[0]);
    return 1;
}

/* plan_swept for the calls that build only what they read: those leave
 * no whole mask whatever they did (a partial one stays kept), so the next
 * plain qrt_planner_plan builds one first. */
static int plan_swept_maskless(struct qrt_planner *pl,
                               const struct qrt_target *start,
                               const struct qrt_target *goal,
                               struct qrt_plan *plan)
{
    if (!plan_swept(pl, start, goal, plan))
        return 0;
    if (pl->mask_state == QRT_MASK_WHOLE)
        pl->mask_state = QRT_MASK_NONE;
    pl->cells_blocked = plan->cells_blocked = -1;
    return 1;
}

/* Start building rows as they are read, with r: from the clusters kept
 * for these points, or from new ones (on a cleared mask). 0 when they do
 * not fit beside the heap (the mask is then cleared and partial). */
static int lazy_start(struct qrt_planner *pl, struct qrt_raster *r)
{
    int kept = pl->mask_state == QRT_MASK_PARTIAL;
    if (!kept)
        start_mask(pl);
    qrt_raster_setup(r, &pl->mask, &pl->collision_arm, pl->radius_m,
                     pl->params.cspace_margin_deg, 0, 1);
    if (kept) { /* the same points: go on from the rows already built */
        qrt_lazy_resume(pl, r);
        return 1;
    }
    if (qrt_lazy_begin(pl, r))
        return 1;
    qrt_lazy_end(pl);
    return 0;
}

/* In pl->check_rows, the mask rows that the motions between consecutive
 * waypoints pass through (the walk that tests a motion marks them, so
 * exactly those). */
static void mark_rows_along(struct qrt_planner *pl,
                            const double (*waypoints_deg)[3], int n)
{
    int i, w;
    for (w = 0; w < QRT_ROW_SET_WORDS; w++)
        pl->check_rows[w] = 0;
    for (i = 0; i + 1 < n; i++)
        qrt_motion_mark_rows(&pl->mask, waypoints_deg[i], waypoints_deg[i + 1],
                             pl->check_rows);
}

/* The rows in pl->check_rows from clusters, kept for a later call on the
 * same points (0: they do not fit, nothing built). */
static int rows_from_clusters(struct qrt_planner *pl)
{
    struct qrt_raster r;
    if (!lazy_start(pl, &r))
        return 0;
    qrt_lazy_build_rows(pl, pl->check_rows);
    (void)qrt_lazy_end(pl);
    return 1;
}

/* Only the mask rows the path passes through, besides any kept from the
 * last call on these points. The mask is partial, hence stale, from here
 * on. */
static void build_rows_along(struct qrt_planner *pl,
                             const double (*waypoints_deg)[3], int n)
{
    mark_rows_along(pl, waypoints_deg, n);
    if (!rows_from_clusters(pl)) {
        start_mask(pl);
        raster_part(pl, 0, 1, pl->check_rows);
    }
}

/* qrt_planner_plan_straight on valid targets: 1 with *plan the straight
 * motion when it is proved free, else 0. */
static int straight_plan(struct qrt_planner *pl, const struct qrt_target *start,
                         const struct qrt_target *goal, struct qrt_plan *plan)
{
    double wp[2][3];
    if (start->kind != QRT_TARGET_JOINTS || goal->kind != QRT_TARGET_JOINTS ||
        !pl->params.simplify || pl->points.dropped > 0)
        return 0;
    /* qrt_planner_plan's own two tests of the straight motion: against
     * the points, then on the rows it passes through with the same mask
     * walk */
    if (plan_swept_maskless(pl, start, goal, plan))
        return 1;
    copy_joints(wp[0], start->value);
    copy_joints(wp[1], goal->value);
    build_rows_along(pl, (const double(*)[3])wp, 2);
    if (!motion_free(pl, wp[0], wp[1]))
        return 0;
    reset_plan(pl, plan);
    plan->cells_blocked = -1; /* the whole mask was never built */
    copy_joints(plan->start_deg, wp[0]);
    copy_joints(plan->goal_deg, wp[1]);
    set_straight_plan(pl, plan, wp[0], wp[1]);
    return 1;
}

int qrt_planner_plan_straight(struct qrt_planner *pl,
                              const struct qrt_target *start,
                              const struct qrt_target *goal,
                              struct qrt_plan *plan, int *straight)
{
    int rc;
    *straight = 0;
    if ((rc = check_targets(pl, start, goal)) != QRT_OK)
        return rc;
    *straight = straight_plan(pl, start, goal, plan);
    return QRT_OK;
}

/* qrt_planner_plan on valid targets and a mask that is built, or being
 * built as it is read. */
static void plan_on_mask(struct qrt_planner *pl, const struct qrt_target *start,
                         const struct qrt_target *goal, struct qrt_plan *plan)
{
    static const double origin[3] = {0.0, 0.0, 0.0};
    struct qrt_ends seeds, goals;
    struct qrt_search_result res;
    enum end_outcome o;
    const double *ref;
    double qs[3], qg[3];
    struct qrt_ik_branch bs, bg;
    long len;
    int merged = pl->points.voxel_m > 0.0, start_stranded, measured;
    double clear_m;

    reset_plan(pl, plan);
    if (pl->points.dropped > 0) {
        set_status(plan, QRT_STATUS_CAPACITY,
                   "more obstacle points than the point table holds");
        return;
    }
    ref = goal->kind == QRT_TARGET_JOINTS ? goal->value : origin;
    o = resolve_end(pl, start, ref, qs, &bs, &seeds, &plan->end_measured,
                    &plan->end_clearance_m);
    if (o != END_UNREACHABLE) {
        copy_joints(plan->start_deg, qs);
        plan->start_ik = bs;
    }
    if (o != END_OK && o != END_STRANDED) {
        set_status(
            plan, end_status(o, 0),
            end_detail(o, 0, start, merged, pl->params.arm.tool_m > 0.0));
        return;
    }
    start_stranded = o == END_STRANDED;
    o = resolve_end(pl, goal, qs, qg, &bg, &goals, &measured, &clear_m);
    if (o != END_UNREACHABLE) {
        copy_joints(plan->goal_deg, qg);
        plan->goal_ik = bg;
    }
    /* a free end the lattice cannot join: the sampled fallback may join
     * the two ends without it; else the first end that failed is told */
    if (start_stranded || o != END_OK) {
        if ((o == END_OK || o == END_STRANDED) &&
            sampled_plan(pl, qs, qg, plan))
            return;
        if (start_stranded)
            o = END_STRANDED;
        else {
            plan->end_measured = measured;
            plan->end_clearance_m = clear_m;
        }
        plan->end_free = o == END_STRANDED;
        set_status(plan, end_status(o, !start_stranded),
                   end_detail(o, !start_stranded, start_stranded ? start : goal,
                              merged, pl->params.arm.tool_m > 0.0));
        return;
    }

    /* replanning in open space: when the straight motion is proved free,
     * it is the shortest path and no search is needed */
    if (pl->params.simplify && motion_free(pl, qs, qg)) {
        set_straight_plan(pl, plan, qs, qg);
        return;
    }
    qrt_search(pl, &seeds, &goals, pl->params.use_astar, &res);
    plan->nodes_expanded = res.expanded;
    if (!res.found) {
        if (!sampled_plan(pl, qs, qg, plan))
            set_status(plan, QRT_STATUS_NO_PATH,
                       pl->params.sample_draws > 0
                           ? "no collision-free path through the lattice, "
                             "and none found by sampling"
                           : "no collision-free path through the lattice");
        return;
    }
    len = qrt_search_path(pl, res.goal_node);
    /* the search adds float costs; the route's length in double is what
     * the simplified path is compared with */
    plan->lattice_cost_deg = route_length(pl, qs, qg, len);
    plan->lattice_path_nodes = len;
    plan->start_node = pl->open.heap[0].node;
    plan->goal_node = res.goal_node;
    if (!emit_route(pl, qs, qg, len, plan)) {
        plan->n_waypoints = 0;
        set_status(plan, QRT_STATUS_CAPACITY,
                   "the path has more waypoints than the plan table holds");
        return;
    }
    plan->cost_deg = route_cost(pl, plan);
    set_status(plan, QRT_STATUS_OK, "path found");
}

int qrt_planner_plan(struct qrt_planner *pl, const struct qrt_target *start,
                     const struct qrt_target *goal, struct qrt_plan *plan)
{
    int rc;
    if ((rc = check_targets(pl, start, goal)) != QRT_OK)
        return rc;
    if (pl->mask_state != QRT_MASK_WHOLE)
        return QRT_E_INVALID;
    if (!plan_swept(pl, start, goal, plan))
        plan_on_mask(pl, start, goal, plan);
    return QRT_OK;
}

/* plan_on_mask with the rows built as they are read; 0 (nothing done)
 * when the clusters do not fit beside the heap. */
static int plan_lazily(struct qrt_planner *pl, const struct qrt_target *start,
                       const struct qrt_target *goal, struct qrt_plan *plan)
{
    struct qrt_raster r;
    if (!lazy_start(pl, &r))
        return 0;
    pl->cells_blocked = -1; /* the whole mask is not built */
    plan_on_mask(pl, start, goal, plan);
    if (qrt_lazy_end(pl)) { /* the heap needed the clusters' room */
        pl->cells_blocked = qrt_mask_count_blocked(&pl->mask);
        plan->cells_blocked = pl->cells_blocked;
    }
    return 1;
}

int qrt_planner_plan_now(struct qrt_planner *pl, const struct qrt_target *start,
                         const struct qrt_target *goal, struct qrt_plan *plan)
{
    int rc;
    if ((rc = check_targets(pl, start, goal)) != QRT_OK)
        return rc;
    if (plan_swept_maskless(pl, start, goal, plan))
        return QRT_OK;
    if (!plan_lazily(pl, start, goal, plan)) {
        qrt_planner_build_mask(pl);
        plan_on_mask(pl, start, goal, plan);
    }
    return QRT_OK;
}

/* Waypoints finite and within the limits? QRT_OK, QRT_E_INVALID or
 * QRT_E_LIMITS. */
static int check_waypoints(const struct qrt_planner *pl,
                           const double (*waypoints_deg)[3], int n)
{
    int i, j;
    if (n < 1)
        return QRT_E_INVALID;
    for (i = 0; i < n; i++) {
        for (j = 0; j < 3; j++)
            if (!isfinite(waypoints_deg[i][j]))
                return QRT_E_INVALID;
        if (qrt_arm_check_joints(&pl->params.arm, waypoints_deg[i]) != QRT_OK)
            return QRT_E_LIMITS;
    }
    return QRT_OK;
}

/* What the quick tests say of the motion a -> b: free on the mask (every
 * row the walk looks at must be built), blocked, or neither (advancement
 * against the points must decide). Where the mask walk fails, the motion
 * most often collides: that configuration and the end of the motion (a
 * new obstacle on the goal) are asked first, a clearance each, before
 * advancement (whose witness search waits QRT_WITNESS_AFTER steps: a
 * path's first and last segments are often connections that only
 * advancement proves, in a step or two). */
enum segment_verdict { SEGMENT_FREE, SEGMENT_BLOCKED, SEGMENT_UNDECIDED };

static enum segment_verdict segment_quick(const struct qrt_planner *pl,
                                          const double a[3], const double b[3])
{
    double radius[3], t_hit;
    if (qrt_motion_free_on_mask_hit(&pl->mask, a, b, &t_hit))
        return SEGMENT_FREE;
    exact_radii(pl, radius);
    if (qrt_motion_collides_at(&pl->collision_arm, radius, &pl->points,
                               &pl->mask.lat, a, b, t_hit) ||
        qrt_motion_collides_at(&pl->collision_arm, radius, &pl->points,
                               &pl->mask.lat, a, b, 1.0))
        return SEGMENT_BLOCKED;
    return SEGMENT_UNDECIDED;
}

/* Does advancement against the points (over block_box's blocks, or
 * NULL) fail to prove the motion a -> b free? */
static int advancement_fails(const struct qrt_planner *pl, const double a[3],
                             const double b[3], const float (*block_box)[6])
{
    double radius[3];
    exact_radii(pl, radius);
    return !qrt_motion_free_exact(&pl->collision_arm, radius, &pl->points,
                                  block_box, &pl->mask.lat, a, b,
                                  QRT_EXACT_MAX_STEPS, QRT_WITNESS_AFTER);
}

/* Is the motion a -> b proved free neither by the quick tests nor by
 * advancement? */
static int segment_blocked(const struct qrt_planner *pl, const double a[3],
                           const double b[3])
{
    enum segment_verdict v = segment_quick(pl, a, b);
    if (v != SEGMENT_UNDECIDED)
        return v == SEGMENT_BLOCKED;
    return advancement_fails(pl, a, b, NULL);
}

/* segment_blocked for qrt_planner_check_path_now, whose path may run near
 * points for long (a sampled path, a join to the lattice): the first time
 * one of its segments needs advancement, the table is put in Morton order
 * and its block boxes made (*boxed then 1), so that advancement passes
 * far blocks over whole, as the sampled fallback's proofs do. The search
 * scratch that holds them is idle in this call. */
static int segment_blocked_now(struct qrt_planner *pl, const double a[3],
                               const double b[3], int *boxed)
{
    enum segment_verdict v = segment_quick(pl, a, b);
    if (v != SEGMENT_UNDECIDED)
        return v == SEGMENT_BLOCKED;
    if (!*boxed) {
        order_points(pl);
        qrt_points_block_boxes(&pl->points, pl->search.block_box);
        *boxed = 1;
    }
    return advancement_fails(pl, a, b, (const float(*)[6])pl->search.block_box);
}

/* The first segment segment_blocked finds, or -1. */
static int first_blocked_segment(const struct qrt_planner *pl,
                                 const double (*waypoints_deg)[3], int n)
{
    int i;
    for (i = 0; i + 1 < n; i++)
        if (segment_blocked(pl, waypoints_deg[i], waypoints_deg[i + 1]))
            return i;
    return -1;
}

int qrt_planner_check_path(const struct qrt_planner *pl,
                           const double (*waypoints_deg)[3], int n,
                           int *first_blocked)
{
    int rc;
    *first_blocked = -1;
    if (pl->mask_state != QRT_MASK_WHOLE)
        return QRT_E_INVALID;
    rc = check_waypoints(pl, waypoints_deg, n);
    if (rc != QRT_OK)
        return rc;
    /* a cloud that lost points to capacity proves nothing free */
    *first_blocked = pl->points.dropped > 0
                         ? 0
                         : first_blocked_segment(pl, waypoints_deg, n);
    return QRT_OK;
}

/* qrt_planner_check_path_now from kept or new clusters, segment by
 * segment, so that a blocked one ends the work: its rows (besides those
 * built already), then its proof. 0 when the clusters do not fit. */
static int check_segments_lazily(struct qrt_planner *pl,
                                 const double (*waypoints_deg)[3], int n,
                                 int *first_blocked)
{
    struct qrt_raster r;
    int i, boxed = 0;
    if (!lazy_start(pl, &r))
        return 0;
    for (i = 0; i + 1 < n; i++) {
        mark_rows_along(pl, waypoints_deg + i, 2);
        qrt_lazy_build_rows(pl, pl->check_rows);
        if (segment_blocked_now(pl, waypoints_deg[i], waypoints_deg[i + 1],
                                &boxed)) {
            *first_blocked = i;
            break;
        }
    }
    (void)qrt_lazy_end(pl);
    return 1;
}

int qrt_planner_check_path_now(struct qrt_planner *pl,
                               const double (*waypoints_deg)[3], int n,
                               int *first_blocked)
{
    int rc, i, boxed = 0;
    *first_blocked = -1;
    rc = check_waypoints(pl, waypoints_deg, n);
    if (rc != QRT_OK)
        return rc;
    if (pl->points.dropped > 0) { /* a cloud that lost points proves nothing */
        start_mask(pl);           /* (and the mask is partial, as promised) */
        *first_blocked = 0;
        return QRT_OK;
    }
    if (check_segments_lazily(pl, waypoints_deg, n, first_blocked))
        return QRT_OK;
    /* the clusters do not fit: the whole path's rows in one pass */
    mark_rows_along(pl, waypoints_deg, n);
    raster_part(pl, 0, 1, pl->check_rows);
    for (i = 0; i + 1 < n; i++)
        if (segment_blocked_now(pl, waypoints_deg[i], waypoints_deg[i + 1],
                                &boxed)) {
            *first_blocked = i;
            break;
        }
    return QRT_OK;
}

double qrt_planner_clearance(const struct qrt_planner *pl,
                             const double q_deg[3], const double *xyz, long n)
{
    double p[QRT_CHAIN_MAX + 1][3], radius[QRT_CHAIN_MAX], best = 1e30;
    long i;
    int k, capsules = qrt_arm_capsules(&pl->params.arm, q_deg,
                                       pl->params.margin_m, p, radius);
    for (i = 0; i < n; i++)
        for (k = 0; k < capsules; k++) {
            double c =
                sqrt(qrt_seg_dist2(xyz + 3 * i, p[k], p[k + 1])) - radius[k];
            if (c < best)
                best = c;
        }
    return best;
}

/* The block boxes lie in the search scratch, which no call keeps; they
 * must not make it larger, and cover the blocks the core's clearance
 * reads. (A negative array size stops the build otherwise.) */
typedef char
    qrti_block_boxes_fit[(long)QRTI_BLOCK_BOXES * 6L <= QRT_MAX_NODES &&
                                 QRTI_POINT_BLOCK == QRT_CLEARANCE_BLOCK &&
                                 QRTI_BLOCK_GROUP == QRT_CLEARANCE_GROUP
                             ? 1
                             : -1];

int qrt_planner_certify_clearance(struct qrt_planner *pl, struct qrt_plan *plan)
{
    double c;
    (void)sizeof(qrti_block_boxes_fit);
    if (plan->status != QRT_STATUS_OK || plan->n_waypoints < 1)
        return QRT_E_INVALID;
    order_points(pl);
    c = qrt_path_clearance(&pl->params.arm, &pl->collision_arm, &pl->points,
                           &pl->mask.lat, pl->search.block_box,
                           (const double(*)[3])plan->waypoints_deg,
                           plan->n_waypoints);
    /* never below the margin, which the path's proof already guarantees
     * (the bound can fall short of the true value by its slack) */
    if (c < QRT_CLEARANCE_NONE_M && c < pl->params.margin_m)
        c = pl->params.margin_m;
    plan->clearance_m = c;
    return QRT_OK;
}
