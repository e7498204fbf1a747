/* A tool on link 3 (docs/spec.md sections Arm, Tool; Collision): the
 * arm's validation of it, the tool tip's forward kinematics against the
 * specification's formula, IK of the tip through the tip arm, the
 * collision arm holding both capsules, the reach, and the planner keeping
 * the tool clear of a point that only the tool can touch. */
#include <math.h>
#include <string.h>

#include "check.h"
#include "qrtplan/qrtplan.h"

static struct qrt_planner pl;

static double dist_seg(const double p[3], const double a[3], const double b[3])
{
    double ab[3], ap[3], t, len2 = 0.0, dot = 0.0, d2 = 0.0;
    int i;
    for (i = 0; i < 3; i++) {
        ab[i] = b[i] - a[i];
        ap[i] = p[i] - a[i];
        len2 += ab[i] * ab[i];
        dot += ap[i] * ab[i];
    }
    t = len2 > 0.0 ? dot / len2 : 0.0;
    t = t < 0.0 ? 0.0 : t > 1.0 ? 1.0 : t;
    for (i = 0; i < 3; i++) {
        double d = ap[i] - t * ab[i];
        d2 += d * d;
    }
    return sqrt(d2);
}

static void tool_arm(struct qrt_arm *arm, double length, double radius)
{
    qrt_arm_default(arm);
    arm->tool_m = length;
    arm->tool_radius_m = radius;
}

static void test_validate(void)
{
    struct qrt_arm arm;
    struct qrt_params prm;
    static const double bad[][2] = {
        {-0.1, 0.02},  {NAN, 0.02},   {INFINITY, 0.02}, {100.5, 0.02},
        {0.1, -0.001}, {0.1, NAN},    {0.1, INFINITY},  {0.1, 10.5},
        {0.0, 0.02},   {-0.0, 1e-12},
    };
    size_t i;
    qrt_arm_default(&arm);
    CHECK(arm.tool_m == 0.0 && arm.tool_radius_m == 0.0, "default has a tool");
    CHECK(qrt_arm_validate(&arm) == QRT_OK, "default arm refused");
    tool_arm(&arm, 0.15, 0.03);
    CHECK(qrt_arm_validate(&arm) == QRT_OK, "a tool refused");
    tool_arm(&arm, 0.15, 0.0);
    CHECK(qrt_arm_validate(&arm) == QRT_OK, "a thin tool refused");
    tool_arm(&arm, 100.0, 10.0);
    CHECK(qrt_arm_validate(&arm) == QRT_OK, "the largest tool refused");
    for (i = 0; i < sizeof bad / sizeof bad[0]; i++) {
        tool_arm(&arm, bad[i][0], bad[i][1]);
        CHECK(qrt_arm_validate(&arm) == QRT_E_INVALID,
              "tool %g m radius %g m accepted", bad[i][0], bad[i][1]);
        qrt_params_default(&prm);
        prm.arm = arm;
        CHECK(qrt_planner_init(&pl, &prm) == QRT_E_INVALID,
              "planner took tool %g m radius %g m", bad[i][0], bad[i][1]);
    }
}

/* The tip by docs/spec.md: Pe + L_t (Pe - P2) / L3; without a tool, Pe. */
static void test_tip_fk(void)
{
    struct qrt_arm arm, none;
    int i, j;
    tool_arm(&arm, 0.2, 0.03);
    qrt_arm_default(&none);
    for (i = 0; i < test_count(5000); i++) {
        double q[3], p[4][3], tip[3], bare[3], err = 0.0, n = 0.0;
        for (j = 0; j < 3; j++)
            q[j] = test_uniform(arm.limit_deg[j][0], arm.limit_deg[j][1]);
        qrt_arm_fk(&arm, q, p);
        qrt_arm_tool_tip(&arm, q, tip);
        for (j = 0; j < 3; j++)
            n += (p[3][j] - p[2][j]) * (p[3][j] - p[2][j]);
        n = sqrt(n);
        for (j = 0; j < 3; j++)
            err = fmax(
                err, fabs(tip[j] - (p[3][j] + 0.2 * (p[3][j] - p[2][j]) / n)));
        CHECK(err < 1e-12, "tip off by %g at (%g %g %g)", err, q[0], q[1],
              q[2]);
        CHECK(fabs(n - arm.link_m[2]) < 1e-12, "link 3 is %g long", n);
        qrt_arm_tool_tip(&none, q, bare);
        qrt_arm_fk(&none, q, p);
        CHECK(memcmp(bare, p[3], sizeof bare) == 0, "no tool: tip is not Pe");
    }
}

/* IK of the tip through the tip arm: every solution puts the tool tip on
 * the point, and the configuration it came from is among them. */
static void test_tip_ik(void)
{
    struct qrt_arm arm, tip_arm;
    int i, j, s, found_all = 1;
    tool_arm(&arm, 0.25, 0.02);
    qrt_arm_tip_arm(&arm, &tip_arm);
    CHECK(tip_arm.link_m[2] == arm.link_m[2] + 0.25 && tip_arm.tool_m == 0.0,
          "tip arm link 3 %g", tip_arm.link_m[2]);
    for (i = 0; i < test_count(5000); i++) {
        double q[3], tip[3], sols[4][3];
        int n, found = 0;
        for (j = 0; j < 3; j++)
            q[j] = test_uniform(arm.limit_deg[j][0], arm.limit_deg[j][1]);
        qrt_arm_tool_tip(&arm, q, tip);
        n = qrt_arm_ik(&tip_arm, tip, q[0], sols);
        CHECK(n >= 1, "no IK of the tip");
        for (s = 0; s < n; s++) {
            double got[3], e = 0.0;
            qrt_arm_tool_tip(&arm, sols[s], got);
            for (j = 0; j < 3; j++)
                e = fmax(e, fabs(got[j] - tip[j]));
            CHECK(e < 1e-9, "tip IK solution misses by %g m", e);
            if (qrt_arm_joint_distance(&arm, sols[s], q) < 1e-6)
                found = 1;
        }
        /* as in test_kinematics.c: a (nearly) straight elbow is where the
         * two branches meet and rounding picks one */
        if (!found && fabs(q[2]) > 1e-3 && fabs(fabs(q[2]) - 180.0) > 1e-3)
            found_all = 0;
    }
    CHECK(found_all, "a configuration missing from its tip's IK");
}

/* The collision arm's link-3 capsule holds link 3's and the tool's; links 1
 * and 2 are the arm's; the reach bounds every capsule. */
static void test_collision_arm(void)
{
    static const double tools[][2] = {{0.2, 0.05}, {0.3, 0.005}, {0.0, 0.0}};
    size_t t;
    for (t = 0; t < sizeof tools / sizeof tools[0]; t++) {
        struct qrt_arm arm, c;
        double reach;
        int i, j, k;
        tool_arm(&arm, tools[t][0], tools[t][1]);
        qrt_arm_collision_arm(&arm, &c);
        reach = qrt_arm_reach_m(&arm);
        CHECK(c.link_m[2] == arm.link_m[2] + tools[t][0], "collision L3 %g",
              c.link_m[2]);
        CHECK(c.link_radius_m[2] == fmax(0.02, tools[t][1]), "collision r3 %g",
              c.link_radius_m[2]);
        CHECK(fabs(reach - (0.96 + tools[t][0] + fmax(0.02, tools[t][1]))) <
                  1e-12,
              "reach %g", reach);
        for (k = 0; k < 2; k++)
            CHECK(c.link_m[k] == arm.link_m[k] &&
                      c.link_radius_m[k] == arm.link_radius_m[k],
                  "link %d changed", k + 1);
        for (i = 0; i < test_count(20000); i++) {
            double q[3], p[4][3], pc[4][3], tip[3], x[3];
            int in_arm, in_coll;
            for (j = 0; j < 3; j++)
                q[j] = test_uniform(arm.limit_deg[j][0], arm.limit_deg[j][1]);
            qrt_arm_fk(&arm, q, p);
            qrt_arm_fk(&c, q, pc);
            qrt_arm_tool_tip(&arm, q, tip);
            /* a point near link 3 or the tool */
            for (j = 0; j < 3; j++)
                x[j] = p[3][j] + test_uniform(-0.4, 0.4);
            in_arm = dist_seg(x, p[2], p[3]) < arm.link_radius_m[2] ||
                     (arm.tool_m > 0.0 &&
                      dist_seg(x, p[3], tip) < arm.tool_radius_m);
            in_coll = dist_seg(x, pc[2], pc[3]) < c.link_radius_m[2];
            CHECK(!in_arm || in_coll, "a point of the arm outside the "
                                      "collision arm");
            CHECK(sqrt(tip[0] * tip[0] + tip[1] * tip[1] + tip[2] * tip[2]) +
                          fmax(arm.tool_radius_m, 0.02) <=
                      reach + 1e-12,
                  "tip beyond the reach");
        }
    }
}

static void target(struct qrt_target *t, enum qrt_target_kind kind, double a,
                   double b, double c)
{
    t->kind = kind;
    t->value[0] = a;
    t->value[1] = b;
    t->value[2] = c;
    t->ik.facing = QRT_FACING_ANY;
    t->ik.elbow = QRT_ELBOW_ANY;
}

/* Least clearance along the plan's segments, sampled every 0.25 degree. */
static double path_clearance(const struct qrt_plan *plan, const double x[3])
{
    double best = 1e30;
    int i, j, s;
    for (i = 0; i + 1 < plan->n_waypoints; i++) {
        const double *a = plan->waypoints_deg[i],
                     *b = plan->waypoints_deg[i + 1];
        double d[3], m = 0.0;
        int n;
        for (j = 0; j < 3; j++) {
            d[j] = b[j] - a[j];
            if (j == 0)
                d[j] = fmod(d[j] + 540.0, 360.0) - 180.0;
            m = fmax(m, fabs(d[j]));
        }
        n = (int)ceil(m / 0.25) + 1;
        for (s = 0; s <= n; s++) {
            double q[3], c;
            for (j = 0; j < 3; j++)
                q[j] = a[j] + d[j] * s / n;
            if (q[0] > 180.0)
                q[0] -= 360.0;
            if (q[0] < -180.0)
                q[0] += 360.0;
            c = qrt_planner_clearance(&pl, q, x, 1);
            best = fmin(best, c);
        }
    }
    return best;
}

/* A point 1.05 m out at alpha 0: beyond the bare arm's reach (0.99 m with
 * radius and margin), on a 0.15 m tool. */
static void test_planner_keeps_the_tool_clear(void)
{
    static const double x[3] = {1.05, 0.0, 0.0};
    static const double zero[3] = {0.0, 0.0, 0.0};
    struct qrt_params prm;
    struct qrt_target s, g;
    struct qrt_plan plan;
    int now;
    target(&s, QRT_TARGET_JOINTS, -60, 0, 0);
    target(&g, QRT_TARGET_JOINTS, 60, 0, 0);
    /* without a tool: ignored as out of reach, the straight sweep is it */
    qrt_params_default(&prm);
    CHECK(qrt_planner_init(&pl, &prm) == QRT_OK, "init");
    qrt_planner_add_points(&pl, x, 1);
    CHECK(qrt_planner_plan_now(&pl, &s, &g, &plan) == QRT_OK &&
              plan.status == QRT_STATUS_OK && plan.n_waypoints == 2 &&
              plan.points_ignored == 1,
          "bare arm: status %d, %d waypoints, %ld ignored", plan.status,
          plan.n_waypoints, plan.points_ignored);
    CHECK(fabs(qrt_planner_clearance(&pl, zero, x, 1) - 0.06) < 1e-12,
          "bare clearance %g", qrt_planner_clearance(&pl, zero, x, 1));
    for (now = 0; now < 2; now++) {
        tool_arm(&prm.arm, 0.15, 0.02);
        CHECK(qrt_planner_init(&pl, &prm) == QRT_OK, "init with a tool");
        qrt_planner_add_points(&pl, x, 1);
        CHECK(fabs(qrt_planner_clearance(&pl, zero, x, 1) + 0.03) < 1e-12,
              "tool clearance %g", qrt_planner_clearance(&pl, zero, x, 1));
        if (!now)
            qrt_planner_build_mask(&pl);
        CHECK((now ? qrt_planner_plan_now(&pl, &s, &g, &plan)
                   : qrt_planner_plan(&pl, &s, &g, &plan)) == QRT_OK &&
                  plan.status == QRT_STATUS_OK && plan.points == 1 &&
                  plan.points_ignored == 0,
              "tool: status %d (%s), %ld points", plan.status, plan.detail,
              plan.points);
        CHECK(path_clearance(&plan, x) > 0.0, "the tool hits the point: %g",
              path_clearance(&plan, x));
    }
    /* a start on the point: blocked, and by the exact rule it collides */
    target(&s, QRT_TARGET_JOINTS, 0, 0, 0);
    CHECK(qrt_planner_plan_now(&pl, &s, &g, &plan) == QRT_OK &&
              plan.status == QRT_STATUS_START_BLOCKED && plan.end_measured &&
              plan.end_clearance_m <= 0.0 &&
              strcmp(plan.detail,
                     "start configuration collides with obstacle points") == 0,
          "start on the tool: %d %s %g", plan.status, plan.detail,
          plan.end_clearance_m);
}

/* A tool wider than link 3 widens the whole of the collision arm's link 3:
 * a point 40 mm from link 3 near the elbow is clear of the rule's capsules
 * (20 mm + 10 mm margin) but not of the collision arm's (50 mm): the start
 * is blocked, measured clear, and the detail says so, naming the tool. */
static void test_wide_tool_is_not_called_a_collision(void)
{
    static const double x[3] = {0.09 + 0.332 + 0.1, 0.0, 0.04};
    struct qrt_params prm;
    struct qrt_target s, g;
    struct qrt_plan plan;
    qrt_params_default(&prm);
    tool_arm(&prm.arm, 0.1, 0.05);
    CHECK(qrt_planner_init(&pl, &prm) == QRT_OK, "init");
    qrt_planner_add_points(&pl, x, 1);
    target(&s, QRT_TARGET_JOINTS, 0, 0, 0);
    target(&g, QRT_TARGET_JOINTS, 90, 0, 0);
    CHECK(qrt_planner_plan_now(&pl, &s, &g, &plan) == QRT_OK &&
              plan.status == QRT_STATUS_START_BLOCKED && plan.end_measured &&
              fabs(plan.end_clearance_m - 0.01) < 1e-6 &&
              strstr(plan.detail, "tool capsule") != NULL,
          "wide tool: %d %s %g", plan.status, plan.detail,
          plan.end_clearance_m);
}

/* A goal for the tool tip: the goal's joints put the tip on it. */
static void test_tool_tip_target(void)
{
    static const double goals[][3] = {
        {0.5, 0.4, 0.3}, {-0.6, 0.2, 0.5}, {0.0, 0.0, 1.0}, {0.3, -0.7, -0.2}};
    struct qrt_params prm;
    struct qrt_target s, g;
    struct qrt_plan plan;
    size_t i;
    qrt_params_default(&prm);
    tool_arm(&prm.arm, 0.15, 0.01);
    for (i = 0; i < sizeof goals / sizeof goals[0]; i++) {
        double tip[3], e = 0.0;
        int j;
        CHECK(qrt_planner_init(&pl, &prm) == QRT_OK, "init");
        target(&s, QRT_TARGET_JOINTS, 0, 30, -30);
        target(&g, QRT_TARGET_TOOL_TIP, goals[i][0], goals[i][1], goals[i][2]);
        CHECK(qrt_planner_plan_now(&pl, &s, &g, &plan) == QRT_OK &&
                  plan.status == QRT_STATUS_OK,
              "tip goal %zu: %d %s", i, plan.status, plan.detail);
        qrt_arm_tool_tip(&prm.arm, plan.goal_deg, tip);
        for (j = 0; j < 3; j++)
            e = fmax(e, fabs(tip[j] - goals[i][j]));
        CHECK(e < 1e-9, "tip goal %zu missed by %g m", i, e);
    }
    /* 0.25 m ahead of the shoulder: within Pe's reach (|L2 - L3| = 0.206
     * m), not the tip's (|L2 - L3 - 0.15| = 0.356 m); behind it, 0.43 m
     * away, only outside the limits */
    target(&g, QRT_TARGET_XYZ, 0.34, 0.0, 0.0);
    CHECK(qrt_planner_plan_now(&pl, &s, &g, &plan) == QRT_OK &&
              plan.status == QRT_STATUS_OK,
          "Pe near the base: %d %s", plan.status, plan.detail);
    g.kind = QRT_TARGET_TOOL_TIP;
    CHECK(qrt_planner_plan_now(&pl, &s, &g, &plan) == QRT_OK &&
              plan.status == QRT_STATUS_UNREACHABLE,
          "tip near the base: %d", plan.status);
    g.kind = (enum qrt_target_kind)3;
    CHECK(qrt_planner_plan_now(&pl, &s, &g, &plan) == QRT_E_INVALID,
          "kind 3 accepted");
}

int main(void)
{
    test_seed(3737);
    test_validate();
    test_tip_fk();
    test_tip_ik();
    test_collision_arm();
    test_planner_keeps_the_tool_clear();
    test_wide_tool_is_not_called_a_collision();
    test_tool_tip_target();
    return test_done("test_tool");
}
