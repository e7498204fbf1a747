/* IK branches (docs/spec.md section Kinematics, Branches): each solution's
 * facing and elbow against the geometry they are defined by, measured on
 * the forward kinematics; the degenerate cases (a point on the base axis,
 * a straight arm, a point straight above the shoulder); and the planner's
 * filter: each requested branch returned when free, and statuses whose
 * detail names the branch when it is out of the limits or blocked. */
#include <string.h>

#include "check.h"
#include "qrtplan/qrtplan.h"

static struct qrt_planner pl;

/* The end effector's horizontal offset along alpha from point from, and its
 * height above it. */
static void in_plane(const double p[3], const double from[3], double alpha_deg,
                     double *u, double *z)
{
    double a = alpha_deg * 3.14159265358979323846 / 180.0;
    *u = (p[0] - from[0]) * cos(a) + (p[1] - from[1]) * sin(a);
    *z = p[2] - from[2];
}

/* Facing and elbow as the definitions state them, on FK positions: the
 * target ahead of or behind the base axis along alpha; the elbow P2 above
 * or below the straight line from P1 to Pe at P2's horizontal place. Cases
 * within tol of the boundary are skipped (0). */
static int facing_measured(double p[4][3], double alpha_deg)
{
    static const double origin[3] = {0.0, 0.0, 0.0};
    double u, z;
    in_plane(p[3], origin, alpha_deg, &u, &z);
    return u > 1e-9 ? QRT_FACING_FRONT : u < -1e-9 ? QRT_FACING_BACK : 0;
}

static int elbow_measured(double p[4][3], double alpha_deg)
{
    double u2, z2, ue, ze, line_z;
    in_plane(p[2], p[1], alpha_deg, &u2, &z2);
    in_plane(p[3], p[1], alpha_deg, &ue, &ze);
    if (fabs(ue) < 1e-6)
        return 0; /* the line is vertical: no above */
    line_z = ze * u2 / ue;
    if (fabs(z2 - line_z) < 1e-6)
        return 0; /* P2 on the line */
    return z2 > line_z ? QRT_ELBOW_UP : QRT_ELBOW_DOWN;
}

static void test_geometry(const struct qrt_arm *arm, const char *name)
{
    long i, seen[4] = {0, 0, 0, 0}; /* front, back, up, down */
    int j, s;
    for (i = 0; i < test_count(20000); i++) {
        double q[3], p[4][3], sols[4][3];
        struct qrt_ik_branch b[4];
        int n;
        for (j = 0; j < 3; j++)
            q[j] = test_uniform(arm->limit_deg[j][0], arm->limit_deg[j][1]);
        qrt_arm_fk(arm, q, p);
        n = qrt_arm_ik_branches(arm, p[3], q[0], sols, b);
        for (s = 0; s < n; s++) {
            double r[4][3];
            int f, e;
            qrt_arm_fk(arm, sols[s], r);
            f = facing_measured(r, sols[s][0]);
            e = elbow_measured(r, sols[s][0]);
            if (f != 0) {
                CHECK((int)b[s].facing == f,
                      "%s: (%g %g %g) is %s, measured %s", name, sols[s][0],
                      sols[s][1], sols[s][2], qrt_ik_facing_name(b[s].facing),
                      qrt_ik_facing_name((enum qrt_ik_facing)f));
                seen[f - 1]++;
            }
            if (e != 0) {
                CHECK((int)b[s].elbow == e,
                      "%s: (%g %g %g) elbow %s, measured %s", name, sols[s][0],
                      sols[s][1], sols[s][2], qrt_ik_elbow_name(b[s].elbow),
                      qrt_ik_elbow_name((enum qrt_ik_elbow)e));
                seen[e + 1]++;
            }
            CHECK(b[s].facing != QRT_FACING_ANY && b[s].elbow != QRT_ELBOW_ANY,
                  "%s: a solution's branch is never ANY", name);
        }
    }
    /* every side was met, many times over, and both ways of "up" in z:
     * ahead of the shoulder and behind it */
    for (j = 0; j < 4; j++)
        CHECK(seen[j] > test_count(20000) / 10, "%s: side %d seen %ld times",
              name, j, seen[j]);
}

/* A point on the base axis: every alpha faces it alike, so each solution
 * is both front and back, and either request allows all of them. */
static void test_on_axis(const struct qrt_arm *arm)
{
    double xyz[3] = {0.0, 0.0, 0.6}, sols[4][3];
    struct qrt_ik_branch b[4], front = {QRT_FACING_FRONT, QRT_ELBOW_ANY};
    struct qrt_ik_branch back = {QRT_FACING_BACK, QRT_ELBOW_ANY};
    int n = qrt_arm_ik_branches(arm, xyz, 30.0, sols, b), s, up = 0, down = 0;
    CHECK(n == 4, "on the axis: %d solutions", n);
    for (s = 0; s < n; s++) {
        CHECK(b[s].facing == QRT_FACING_BOTH, "on the axis: facing %s",
              qrt_ik_facing_name(b[s].facing));
        CHECK(qrt_ik_branch_allows(&front, &b[s]) &&
                  qrt_ik_branch_allows(&back, &b[s]),
              "on the axis: front and back both allow solution %d", s);
        up += b[s].elbow == QRT_ELBOW_UP;
        down += b[s].elbow == QRT_ELBOW_DOWN;
    }
    /* the elbow is still told apart: the point is behind the shoulder */
    CHECK(up == 2 && down == 2, "on the axis: %d up, %d down", up, down);
}

/* A straight arm (c = 1, the point at full reach): one solution, P2 on the
 * line P1-Pe, both elbows. */
static void test_straight_arm(const struct qrt_arm *arm)
{
    /* just past full reach, inside IK's tolerance, so that c is clamped
     * to exactly 1 */
    double xyz[3], sols[4][3];
    struct qrt_ik_branch b[4], up = {QRT_FACING_ANY, QRT_ELBOW_UP};
    struct qrt_ik_branch down = {QRT_FACING_ANY, QRT_ELBOW_DOWN};
    int n;
    xyz[0] = arm->link_m[0] + arm->link_m[1] + arm->link_m[2] + 1e-13;
    xyz[1] = 0.0;
    xyz[2] = 0.0;
    n = qrt_arm_ik_branches(arm, xyz, 0.0, sols, b);
    CHECK(n == 1, "straight arm: %d solutions", n);
    if (n != 1)
        return;
    CHECK(b[0].facing == QRT_FACING_FRONT && b[0].elbow == QRT_ELBOW_BOTH,
          "straight arm: %s %s", qrt_ik_facing_name(b[0].facing),
          qrt_ik_elbow_name(b[0].elbow));
    CHECK(qrt_ik_branch_allows(&up, &b[0]) &&
              qrt_ik_branch_allows(&down, &b[0]),
          "straight arm: up and down both allow it");
}

/* The end effector straight above the shoulder (u = 0): the line P1-Pe is
 * vertical, so neither elbow is above it; both facing front are BOTH, while
 * those facing back (u = -2 L1) are told apart. */
static void test_above_shoulder(const struct qrt_arm *arm)
{
    double xyz[3], sols[4][3];
    struct qrt_ik_branch b[4];
    int n, s, front = 0, back_up = 0, back_down = 0;
    xyz[0] = arm->link_m[0];
    xyz[1] = 0.0;
    xyz[2] = 0.5;
    n = qrt_arm_ik_branches(arm, xyz, 0.0, sols, b);
    for (s = 0; s < n; s++) {
        if (b[s].facing == QRT_FACING_FRONT) {
            CHECK(b[s].elbow == QRT_ELBOW_BOTH, "above the shoulder: %s",
                  qrt_ik_elbow_name(b[s].elbow));
            front++;
        }
        back_up += b[s].facing == QRT_FACING_BACK && b[s].elbow == QRT_ELBOW_UP;
        back_down +=
            b[s].facing == QRT_FACING_BACK && b[s].elbow == QRT_ELBOW_DOWN;
    }
    CHECK(front == 2 && back_up + back_down >= 1,
          "above the shoulder: %d front, %d back up, %d back down", front,
          back_up, back_down);
}

static void test_requests(void)
{
    struct qrt_ik_branch r, sol;
    int f, e;
    for (f = -1; f <= 4; f++)
        for (e = -1; e <= 4; e++) {
            int valid = f >= 0 && f <= 2 && e >= 0 && e <= 2;
            r.facing = (enum qrt_ik_facing)f;
            r.elbow = (enum qrt_ik_elbow)e;
            CHECK((qrt_ik_branch_check(&r) == QRT_OK) == valid,
                  "request (%d, %d) %s", f, e, valid ? "refused" : "taken");
        }
    /* a request allows a solution when each field is ANY or shared */
    sol.facing = QRT_FACING_FRONT;
    sol.elbow = QRT_ELBOW_BOTH;
    for (f = 0; f <= 2; f++)
        for (e = 0; e <= 2; e++) {
            int expect = f != QRT_FACING_BACK;
            r.facing = (enum qrt_ik_facing)f;
            r.elbow = (enum qrt_ik_elbow)e;
            CHECK(qrt_ik_branch_allows(&r, &sol) == expect,
                  "(%d, %d) allows front/both: %d", f, e, !expect);
        }
    CHECK(strcmp(qrt_ik_facing_name(QRT_FACING_FRONT), "front") == 0 &&
              strcmp(qrt_ik_facing_name(QRT_FACING_BACK), "back") == 0 &&
              strcmp(qrt_ik_facing_name(QRT_FACING_ANY), "any") == 0 &&
              strcmp(qrt_ik_facing_name(QRT_FACING_BOTH), "both") == 0 &&
              strcmp(qrt_ik_elbow_name(QRT_ELBOW_UP), "up") == 0 &&
              strcmp(qrt_ik_elbow_name(QRT_ELBOW_DOWN), "down") == 0,
          "names");
}

/* The four solutions of this point all lie inside the default limits. */
static const double four_way[3] = {0.6, 0.0, 0.45};

/* Plan from joints (0, 0, 0) to four_way with the goal's branch request
 * (facing, elbow), as qrt_planner_plan_now or, whole, qrt_planner_plan. */
static int plan_to(const struct qrt_params *prm, const double *cloud, long n,
                   int facing, int elbow, int whole, struct qrt_plan *plan)
{
    struct qrt_target s = {
        QRT_TARGET_JOINTS, {0, 0, 0}, {QRT_FACING_ANY, QRT_ELBOW_ANY}};
    struct qrt_target g = {
        QRT_TARGET_XYZ, {0, 0, 0}, {QRT_FACING_ANY, QRT_ELBOW_ANY}};
    int k;
    for (k = 0; k < 3; k++)
        g.value[k] = four_way[k];
    g.ik.facing = (enum qrt_ik_facing)facing;
    g.ik.elbow = (enum qrt_ik_elbow)elbow;
    if (qrt_planner_init(&pl, prm) != QRT_OK)
        return QRT_E_INVALID;
    qrt_planner_add_points(&pl, cloud, n);
    if (!whole)
        return qrt_planner_plan_now(&pl, &s, &g, plan);
    qrt_planner_build_mask(&pl);
    return qrt_planner_plan(&pl, &s, &g, plan);
}

/* Each branch asked for is the one planned to, free space or not, and the
 * default is today's rule: the solution nearest the start. */
static void test_each_branch_planned(void)
{
    static struct qrt_plan plan;
    static const double far_points[3] = {-0.5, -0.5, -0.5};
    struct qrt_params prm;
    double sols[4][3], best = 1e300;
    struct qrt_ik_branch b[4];
    static const double zero[3] = {0, 0, 0};
    int n, s, whole, nearest = 0;
    qrt_params_default(&prm);
    n = qrt_arm_ik_branches(&prm.arm, four_way, 0.0, sols, b);
    CHECK(n == 4, "four_way: %d solutions", n);
    for (s = 0; s < n; s++) {
        double d = qrt_arm_joint_distance(&prm.arm, zero, sols[s]);
        if (d < best) {
            best = d;
            nearest = s;
        }
    }
    for (whole = 0; whole <= 1; whole++)
        for (s = 0; s < n; s++) {
            int rc = plan_to(&prm, far_points, 1, b[s].facing, b[s].elbow,
                             whole, &plan);
            CHECK(rc == QRT_OK && plan.status == QRT_STATUS_OK,
                  "branch %s/%s: rc %d status %s",
                  qrt_ik_facing_name(b[s].facing),
                  qrt_ik_elbow_name(b[s].elbow), rc,
                  qrt_plan_status_name(plan.status));
            CHECK(plan.goal_ik.facing == b[s].facing &&
                      plan.goal_ik.elbow == b[s].elbow &&
                      qrt_arm_joint_distance(&prm.arm, plan.goal_deg, sols[s]) <
                          1e-9,
                  "asked %s/%s, planned to %s/%s (%g %g %g)",
                  qrt_ik_facing_name(b[s].facing),
                  qrt_ik_elbow_name(b[s].elbow),
                  qrt_ik_facing_name(plan.goal_ik.facing),
                  qrt_ik_elbow_name(plan.goal_ik.elbow), plan.goal_deg[0],
                  plan.goal_deg[1], plan.goal_deg[2]);
            CHECK(plan.start_ik.facing == QRT_FACING_ANY &&
                      plan.start_ik.elbow == QRT_ELBOW_ANY,
                  "a joints start has no branch");
        }
    plan_to(&prm, far_points, 1, QRT_FACING_ANY, QRT_ELBOW_ANY, 0, &plan);
    CHECK(plan.status == QRT_STATUS_OK &&
              qrt_arm_joint_distance(&prm.arm, plan.goal_deg, sols[nearest]) <
                  1e-9 &&
              plan.goal_ik.facing == b[nearest].facing &&
              plan.goal_ik.elbow == b[nearest].elbow,
          "any/any: the nearest solution");
    /* facing alone: the nearer of the two facing back */
    plan_to(&prm, far_points, 1, QRT_FACING_BACK, QRT_ELBOW_ANY, 0, &plan);
    CHECK(plan.status == QRT_STATUS_OK &&
              plan.goal_ik.facing == QRT_FACING_BACK,
          "back/any: %s", qrt_ik_facing_name(plan.goal_ik.facing));
}

/* A start given as a point takes its requested branch too. */
static void test_start_branch(void)
{
    static struct qrt_plan plan;
    static const double far_points[3] = {-0.5, -0.5, -0.5};
    struct qrt_params prm;
    struct qrt_target s = {
        QRT_TARGET_XYZ, {0.6, 0.0, 0.45}, {QRT_FACING_BACK, QRT_ELBOW_DOWN}};
    struct qrt_target g = {
        QRT_TARGET_JOINTS, {90, 0, 0}, {QRT_FACING_ANY, QRT_ELBOW_ANY}};
    qrt_params_default(&prm);
    qrt_planner_init(&pl, &prm);
    qrt_planner_add_points(&pl, far_points, 1);
    CHECK(qrt_planner_plan_now(&pl, &s, &g, &plan) == QRT_OK &&
              plan.status == QRT_STATUS_OK &&
              plan.start_ik.facing == QRT_FACING_BACK &&
              plan.start_ik.elbow == QRT_ELBOW_DOWN &&
              plan.goal_ik.facing == QRT_FACING_ANY,
          "start back/down: %s, %s/%s", qrt_plan_status_name(plan.status),
          qrt_ik_facing_name(plan.start_ik.facing),
          qrt_ik_elbow_name(plan.start_ik.elbow));
    /* a request outside the enums is an error, for xyz targets only */
    s.ik.facing = QRT_FACING_BOTH;
    CHECK(qrt_planner_plan_now(&pl, &s, &g, &plan) == QRT_E_INVALID,
          "facing BOTH is no request");
    s.ik.facing = QRT_FACING_ANY;
    s.ik.elbow = (enum qrt_ik_elbow)7;
    CHECK(qrt_planner_plan_now(&pl, &s, &g, &plan) == QRT_E_INVALID,
          "elbow 7 is no request");
    g.ik = s.ik; /* a joints target's ik is not read */
    s.ik.elbow = QRT_ELBOW_ANY;
    CHECK(qrt_planner_plan_now(&pl, &s, &g, &plan) == QRT_OK,
          "joints target with an ik");
}

/* The requested branch outside the limits: unreachable, named. */
static void test_branch_unreachable(void)
{
    static struct qrt_plan plan;
    static const double far_points[3] = {-0.5, -0.5, -0.5};
    struct qrt_params prm;
    qrt_params_default(&prm);
    prm.arm.limit_deg[1][1] = 100.0; /* no reaching back over the head */
    plan_to(&prm, far_points, 1, QRT_FACING_BACK, QRT_ELBOW_UP, 0, &plan);
    CHECK(plan.status == QRT_STATUS_UNREACHABLE &&
              strcmp(plan.detail, "goal point has no IK solution facing back "
                                  "with the elbow up inside the arm's reach "
                                  "and limits") == 0,
          "back/up outside the limits: %s: %s",
          qrt_plan_status_name(plan.status), plan.detail);
    plan_to(&prm, far_points, 1, QRT_FACING_FRONT, QRT_ELBOW_UP, 0, &plan);
    CHECK(plan.status == QRT_STATUS_OK &&
              plan.goal_ik.facing == QRT_FACING_FRONT &&
              plan.goal_ik.elbow == QRT_ELBOW_UP,
          "front/up inside them: %s", qrt_plan_status_name(plan.status));
    plan_to(&prm, far_points, 1, QRT_FACING_ANY, QRT_ELBOW_ANY, 0, &plan);
    CHECK(plan.status == QRT_STATUS_OK, "any/any: %s",
          qrt_plan_status_name(plan.status));
}

/* The requested branch blocked (points around its elbow) while others are
 * free: goal_blocked, named, with that branch's configuration. */
static void test_branch_blocked(void)
{
    static struct qrt_plan plan;
    static double cloud[3 * 64];
    struct qrt_params prm;
    double sols[4][3], p[4][3];
    struct qrt_ik_branch b[4];
    int n, s, k, up = -1;
    long m = 0;
    qrt_params_default(&prm);
    n = qrt_arm_ik_branches(&prm.arm, four_way, 0.0, sols, b);
    for (s = 0; s < n; s++)
        if (b[s].facing == QRT_FACING_FRONT && b[s].elbow == QRT_ELBOW_UP)
            up = s;
    CHECK(up >= 0, "four_way has a front/up solution");
    if (up < 0)
        return;
    qrt_arm_fk(&prm.arm, sols[up], p);
    for (k = 0; k < 64; k++, m++) { /* a small ball around its elbow */
        double t = 0.7 * k, h = -1.0 + 2.0 * (k + 0.5) / 64.0;
        double r = sqrt(1.0 - h * h);
        cloud[3 * m] = p[2][0] + 0.03 * r * cos(t);
        cloud[3 * m + 1] = p[2][1] + 0.03 * r * sin(t);
        cloud[3 * m + 2] = p[2][2] + 0.03 * h;
    }
    plan_to(&prm, cloud, m, QRT_FACING_FRONT, QRT_ELBOW_UP, 0, &plan);
    CHECK(plan.status == QRT_STATUS_GOAL_BLOCKED &&
              strcmp(plan.detail, "every goal configuration facing front "
                                  "with the elbow up collides with obstacle "
                                  "points") == 0 &&
              plan.goal_ik.facing == QRT_FACING_FRONT &&
              plan.goal_ik.elbow == QRT_ELBOW_UP,
          "front/up blocked: %s: %s", qrt_plan_status_name(plan.status),
          plan.detail);
    plan_to(&prm, cloud, m, QRT_FACING_ANY, QRT_ELBOW_ANY, 0, &plan);
    CHECK(plan.status == QRT_STATUS_OK &&
              !(plan.goal_ik.facing == QRT_FACING_FRONT &&
                plan.goal_ik.elbow == QRT_ELBOW_UP),
          "any/any goes round it: %s", qrt_plan_status_name(plan.status));
    plan_to(&prm, cloud, m, QRT_FACING_FRONT, QRT_ELBOW_DOWN, 1, &plan);
    CHECK(plan.status == QRT_STATUS_OK &&
              plan.goal_ik.facing == QRT_FACING_FRONT &&
              plan.goal_ik.elbow == QRT_ELBOW_DOWN,
          "front/down free: %s", qrt_plan_status_name(plan.status));
}

int main(void)
{
    struct qrt_arm arm;
    test_seed(3737);
    qrt_arm_default(&arm);
    test_geometry(&arm, "default arm");
    test_on_axis(&arm);
    test_straight_arm(&arm);
    test_above_shoulder(&arm);
    /* a longer L1, alpha limited, sigma and eta over the whole circle */
    arm.link_m[0] = 0.25;
    arm.limit_deg[0][0] = -170.0;
    arm.limit_deg[0][1] = 170.0;
    arm.limit_deg[1][0] = arm.limit_deg[2][0] = -180.0;
    arm.limit_deg[1][1] = arm.limit_deg[2][1] = 180.0;
    test_geometry(&arm, "long shoulder");
    test_requests();
    test_each_branch_planned();
    test_start_branch();
    test_branch_unreachable();
    test_branch_blocked();
    return test_done("test_ik_branch");
}
