#define _POSIX_C_SOURCE 200809L
/* The Python package's flat C layer (python/qrtplan/_core.py loads it with
 * ctypes; docs/python.md says why). It holds no planning logic: it turns
 * plain records of doubles and longs, whose layout Python can state
 * without the core's headers, into the core's structs, calls the core, and
 * copies the answers back. The planner's state (struct qrt_planner, ~15.7
 * MB in the host profile) is allocated here, outside the core, once per
 * Python Planner. Built only as a shared library for the package. */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "end_check.h"
#include "qrtplan/planner.h"

/* An arm as plain doubles (struct qrt_arm's fields, limits flattened). */
struct qrtpy_arm {
    double link_m[3];
    double link_radius_m[3];
    double limit_deg[6]; /* alpha lo, hi, sigma lo, hi, eta lo, hi */
    double tool_m;
    double tool_radius_m;
};

struct qrtpy_params {
    struct qrtpy_arm arm;
    double margin_m;
    double cspace_margin_deg;
    double grid_deg;
    long use_astar;
    long simplify;
    long sample_draws;
};

struct qrtpy_target {
    long kind; /* enum qrt_target_kind */
    double value[3];
    long facing, elbow;
};

#define QRTPY_DETAIL_LEN 256

struct qrtpy_result {
    long status;
    long n_waypoints;
    double cost_deg, lattice_cost_deg;
    double start_deg[3], goal_deg[3];
    long start_facing, start_elbow, goal_facing, goal_elbow;
    long start_node, goal_node, lattice_path_nodes, nodes_expanded;
    long sampled_nodes;
    long cells_blocked, points, points_ignored, points_dropped;
    double voxel_m;
    long end_free, end_measured;
    double end_clearance_m;
    /* an ok plan's certified clearance (qrt_planner_certify_clearance);
     * has_clearance 0 when there is none: not ok, or no point given
     * (QRT_CLEARANCE_NONE_M, the CLI's null) */
    long has_clearance;
    double clearance_m;
    double c_seconds; /* wall time inside qrtpy_plan */
    char detail[QRTPY_DETAIL_LEN];
};

/* The sizes Python checks its ctypes records against, and the build's
 * table sizes. */
void qrtpy_layout(long out[6])
{
    out[0] = (long)sizeof(struct qrtpy_arm);
    out[1] = (long)sizeof(struct qrtpy_params);
    out[2] = (long)sizeof(struct qrtpy_target);
    out[3] = (long)sizeof(struct qrtpy_result);
    out[4] = (long)QRT_MAX_WAYPOINTS;
    out[5] = (long)QRT_MAX_POINTS;
}

static void arm_in(const struct qrtpy_arm *a, struct qrt_arm *arm)
{
    int j;
    for (j = 0; j < 3; j++) {
        arm->link_m[j] = a->link_m[j];
        arm->link_radius_m[j] = a->link_radius_m[j];
        arm->limit_deg[j][0] = a->limit_deg[2 * j];
        arm->limit_deg[j][1] = a->limit_deg[2 * j + 1];
    }
    arm->tool_m = a->tool_m;
    arm->tool_radius_m = a->tool_radius_m;
}

static void arm_out(const struct qrt_arm *arm, struct qrtpy_arm *a)
{
    int j;
    for (j = 0; j < 3; j++) {
        a->link_m[j] = arm->link_m[j];
        a->link_radius_m[j] = arm->link_radius_m[j];
        a->limit_deg[2 * j] = arm->limit_deg[j][0];
        a->limit_deg[2 * j + 1] = arm->limit_deg[j][1];
    }
    a->tool_m = arm->tool_m;
    a->tool_radius_m = arm->tool_radius_m;
}

static void params_in(const struct qrtpy_params *p, struct qrt_params *prm)
{
    arm_in(&p->arm, &prm->arm);
    prm->margin_m = p->margin_m;
    prm->cspace_margin_deg = p->cspace_margin_deg;
    prm->grid_deg = p->grid_deg;
    prm->use_astar = (int)p->use_astar;
    prm->simplify = (int)p->simplify;
    prm->sample_draws = p->sample_draws;
}

/* The core's defaults (qrt_params_default). */
void qrtpy_params_default(struct qrtpy_params *p)
{
    struct qrt_params prm;
    qrt_params_default(&prm);
    arm_out(&prm.arm, &p->arm);
    p->margin_m = prm.margin_m;
    p->cspace_margin_deg = prm.cspace_margin_deg;
    p->grid_deg = prm.grid_deg;
    p->use_astar = prm.use_astar;
    p->simplify = prm.simplify;
    p->sample_draws = prm.sample_draws;
}

struct qrtpy_planner {
    struct qrt_planner pl;
    struct qrt_params params;
};

/* A planner on the heap, initialised: NULL with *rc the core's error (and
 * msg its sentence for QRT_E_ABI, else "") when init fails or memory is
 * short (QRT_E_TOO_BIG then, msg "out of memory"). */
void *qrtpy_planner_new(const struct qrtpy_params *p, int *rc, char *msg,
                        size_t msg_len)
{
    struct qrtpy_planner *h = calloc(1, sizeof *h);
    if (msg_len > 0)
        msg[0] = '\0';
    if (!h) {
        *rc = QRT_E_TOO_BIG;
        snprintf(msg, msg_len, "out of memory");
        return NULL;
    }
    params_in(p, &h->params);
    *rc = qrt_planner_init(&h->pl, &h->params);
    if (*rc != QRT_OK) {
        if (*rc == QRT_E_ABI)
            (void)qrt_abi_message(msg, msg_len);
        free(h);
        return NULL;
    }
    return h;
}

void qrtpy_planner_free(void *h)
{
    free(h);
}

static void target_in(const struct qrtpy_target *t, struct qrt_target *out)
{
    out->kind = (enum qrt_target_kind)t->kind;
    out->value[0] = t->value[0];
    out->value[1] = t->value[1];
    out->value[2] = t->value[2];
    out->ik.facing = (enum qrt_ik_facing)t->facing;
    out->ik.elbow = (enum qrt_ik_elbow)t->elbow;
}

static double now_s(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

/* Replace the planner's points with xyz (3n doubles) and plan from start
 * to goal, as `qrtplan plan` does: the plan built as read, or on the whole
 * mask when whole_mask is 1; an ok plan's clearance certified
 * (qrt_planner_certify_clearance, inside c_seconds); a blocked end the core
 * could not measure (merged points) is measured against xyz as given, with
 * the CLI's sentence. waypoints receives n_waypoints rows of 3 doubles (room
 * for QRT_MAX_WAYPOINTS). Returns QRT_OK or the core's error. */
int qrtpy_plan(void *handle, const double *xyz, long n,
               const struct qrtpy_target *start,
               const struct qrtpy_target *goal, int whole_mask,
               struct qrtpy_result *r, double *waypoints)
{
    struct qrtpy_planner *h = (struct qrtpy_planner *)handle;
    struct qrt_target s, g;
    struct qrt_plan plan;
    struct end_check c;
    double t0 = now_s();
    int rc, i;
    target_in(start, &s);
    target_in(goal, &g);
    qrt_planner_clear_points(&h->pl);
    rc = qrt_planner_add_points(&h->pl, xyz, n);
    if (rc != QRT_OK)
        return rc;
    if (whole_mask) {
        rc = qrt_planner_build_mask(&h->pl);
        if (rc == QRT_OK)
            rc = qrt_planner_plan(&h->pl, &s, &g, &plan);
    } else
        rc = qrt_planner_plan_now(&h->pl, &s, &g, &plan);
    if (rc != QRT_OK)
        return rc;
    /* on the table the plan was made on, as `qrtplan plan` does */
    r->has_clearance = 0;
    r->clearance_m = 0.0;
    if (plan.status == QRT_STATUS_OK) {
        rc = qrt_planner_certify_clearance(&h->pl, &plan);
        if (rc != QRT_OK)
            return rc;
        r->has_clearance = plan.clearance_m < QRT_CLEARANCE_NONE_M;
        r->clearance_m = plan.clearance_m;
    }
    /* the sentence `qrtplan plan` writes (src/cli/plan_json.c) */
    if (plan.status == QRT_STATUS_CAPACITY && plan.points_dropped > 0)
        snprintf(r->detail, sizeof r->detail,
                 "%ld obstacle points dropped: more than the point table "
                 "holds even as %.0f mm voxels; not planning on a partial "
                 "cloud",
                 plan.points_dropped, 1000.0 * plan.voxel_m);
    else
        snprintf(r->detail, sizeof r->detail, "%s", plan.detail);
    if (end_check_needed(&plan)) {
        end_check_begin(&c, &h->pl, &h->params.arm, &plan, &s, &g);
        end_check_add(&c, xyz, n);
        plan.end_measured = 1;
        plan.end_clearance_m = end_check_clearance(&c);
    }
    if (end_check_measured(&plan))
        end_check_detail(&plan,
                         plan.status == QRT_STATUS_GOAL_BLOCKED ? &g : &s,
                         &h->params, r->detail, sizeof r->detail);
    r->status = plan.status;
    r->n_waypoints = plan.n_waypoints;
    for (i = 0; i < plan.n_waypoints; i++) {
        waypoints[3 * i] = plan.waypoints_deg[i][0];
        waypoints[3 * i + 1] = plan.waypoints_deg[i][1];
        waypoints[3 * i + 2] = plan.waypoints_deg[i][2];
    }
    r->cost_deg = plan.cost_deg;
    r->lattice_cost_deg = plan.lattice_cost_deg;
    for (i = 0; i < 3; i++) {
        r->start_deg[i] = plan.start_deg[i];
        r->goal_deg[i] = plan.goal_deg[i];
    }
    r->start_facing = plan.start_ik.facing;
    r->start_elbow = plan.start_ik.elbow;
    r->goal_facing = plan.goal_ik.facing;
    r->goal_elbow = plan.goal_ik.elbow;
    r->start_node = plan.start_node;
    r->goal_node = plan.goal_node;
    r->lattice_path_nodes = plan.lattice_path_nodes;
    r->nodes_expanded = plan.nodes_expanded;
    r->sampled_nodes = plan.sampled_nodes;
    r->cells_blocked = plan.cells_blocked;
    r->points = plan.points;
    r->points_ignored = plan.points_ignored;
    r->points_dropped = plan.points_dropped;
    r->voxel_m = plan.voxel_m;
    r->end_free = plan.end_free;
    r->end_measured = plan.end_measured;
    r->end_clearance_m = plan.end_clearance_m;
    r->c_seconds = now_s() - t0;
    return QRT_OK;
}

/* --- kinematics: the core's arm functions ------------------------------ */

int qrtpy_arm_default(struct qrtpy_arm *a)
{
    struct qrt_arm arm;
    qrt_arm_default(&arm);
    arm_out(&arm, a);
    return QRT_OK;
}

int qrtpy_arm_validate(const struct qrtpy_arm *a)
{
    struct qrt_arm arm;
    arm_in(a, &arm);
    return qrt_arm_validate(&arm);
}

/* P0 (base of link 1), P1, P2, Pe and the tool tip (Pe without a tool). */
int qrtpy_forward_points(const struct qrtpy_arm *a, const double q_deg[3],
                         double out[5][3])
{
    struct qrt_arm arm;
    double p[4][3];
    int i, j, rc;
    arm_in(a, &arm);
    if ((rc = qrt_arm_validate(&arm)) != QRT_OK)
        return rc;
    qrt_arm_fk(&arm, q_deg, p);
    for (i = 0; i < 4; i++)
        for (j = 0; j < 3; j++)
            out[i][j] = p[i][j];
    qrt_arm_tool_tip(&arm, q_deg, out[4]);
    return QRT_OK;
}

/* The capsules the planner checks (qrt_arm_collision_arm): link i from
 * p[i] to p[i + 1] with radius r[i], i = 0..2. */
int qrtpy_capsules(const struct qrtpy_arm *a, const double q_deg[3],
                   double p[4][3], double r[3])
{
    struct qrt_arm arm, col;
    int i, rc;
    arm_in(a, &arm);
    if ((rc = qrt_arm_validate(&arm)) != QRT_OK)
        return rc;
    qrt_arm_collision_arm(&arm, &col);
    qrt_arm_fk(&col, q_deg, p);
    for (i = 0; i < 3; i++)
        r[i] = col.link_radius_m[i];
    return QRT_OK;
}

/* Every IK solution within the limits (qrt_arm_ik_branches); *n the count,
 * branches[2i], [2i + 1] the facing and elbow of solution i. */
int qrtpy_ik(const struct qrtpy_arm *a, const double xyz_m[3],
             double alpha_hint_deg, double sol[4][3], long branches[8], int *n)
{
    struct qrt_arm arm;
    struct qrt_ik_branch b[4];
    int i, rc;
    arm_in(a, &arm);
    if ((rc = qrt_arm_validate(&arm)) != QRT_OK)
        return rc;
    *n = qrt_arm_ik_branches(&arm, xyz_m, alpha_hint_deg, sol, b);
    for (i = 0; i < *n; i++) {
        branches[2 * i] = b[i].facing;
        branches[2 * i + 1] = b[i].elbow;
    }
    return QRT_OK;
}

int qrtpy_check_joints(const struct qrtpy_arm *a, const double q_deg[3])
{
    struct qrt_arm arm;
    int rc;
    arm_in(a, &arm);
    if ((rc = qrt_arm_validate(&arm)) != QRT_OK)
        return rc;
    return qrt_arm_check_joints(&arm, q_deg);
}

double qrtpy_clearance(void *handle, const double q_deg[3], const double *xyz,
                       long n)
{
    struct qrtpy_planner *h = (struct qrtpy_planner *)handle;
    return qrt_planner_clearance(&h->pl, q_deg, xyz, n);
}
