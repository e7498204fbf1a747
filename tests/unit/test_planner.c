/* End-to-end plans checked by the independent reference arm: every
 * returned path, sampled at 0.05 degrees per joint, stays inside the limits
 * and collides with nothing; each status comes when it should; and a caller
 * compiled with other settings than the library is refused. */
#include <limits.h>
#include <string.h>

#include "check.h"
#include "qrtplan/qrtplan.h"
#include "ref_arm.h"

static struct qrt_planner pl;
static double cloud[3 * 4000];

static double wrap180(double x)
{
    x = fmod(x, 360.0);
    if (x <= -180.0)
        x += 360.0;
    if (x > 180.0)
        x -= 360.0;
    return x;
}

/* Worst clearance along the path; limit violations count as -1. */
static double path_clearance(const struct qrt_plan *plan, const double *pts,
                             long n, const double radius[3])
{
    double worst = 1e30;
    int i;
    for (i = 1; i < plan->n_waypoints; i++) {
        const double *a = plan->waypoints_deg[i - 1];
        const double *b = plan->waypoints_deg[i];
        double d[3], span = 0.0;
        int j, k, steps;
        d[0] = wrap180(b[0] - a[0]);
        d[1] = b[1] - a[1];
        d[2] = b[2] - a[2];
        for (j = 0; j < 3; j++)
            span = fmax(span, fabs(d[j]));
        steps = (int)ceil(span / 0.05) + 1;
        for (k = 0; k <= steps; k++) {
            double q[3], t = (double)k / steps, c;
            for (j = 0; j < 3; j++)
                q[j] = a[j] + t * d[j];
            q[0] = wrap180(q[0]);
            if (q[1] < -40.0 - 1e-9 || q[1] > 180.0 + 1e-9 ||
                q[2] < -180.0 - 1e-9 || q[2] > 140.0 + 1e-9)
                return -1.0;
            c = ref_clearance(q, pts, n, radius);
            worst = fmin(worst, c);
        }
    }
    return worst;
}

static long sphere(double *out, double cx, double cy, double cz, double r,
                   int k)
{
    long n = 0;
    int i, j;
    for (i = 0; i < k; i++)
        for (j = 0; j < k; j++) {
            double t1 = -3.14159265 + 6.2831853 * i / k;
            double t2 = -1.5707963 + 3.14159265 * j / (k - 1);
            out[3 * n] = cx + r * cos(t1) * cos(t2);
            out[3 * n + 1] = cy + r * sin(t1) * cos(t2);
            out[3 * n + 2] = cz + r * sin(t2);
            n++;
        }
    return n;
}

static void random_joints(double q[3])
{
    q[0] = test_uniform(-180, 180);
    q[1] = test_uniform(-40, 180);
    q[2] = test_uniform(-180, 140);
}

static void test_random_scenes(void)
{
    int trial, solved = 0;
    double radius[3] = {0.03, 0.03, 0.03};
    for (trial = 0; trial < test_count(150); trial++) {
        struct qrt_params prm;
        struct qrt_target s = {
            QRT_TARGET_JOINTS, {0, 0, 0}, {QRT_FACING_ANY, QRT_ELBOW_ANY}};
        struct qrt_target g = {
            QRT_TARGET_JOINTS, {0, 0, 0}, {QRT_FACING_ANY, QRT_ELBOW_ANY}};
        struct qrt_plan plan;
        long n = 0;
        int k, spheres = 1 + trial % 5;
        qrt_params_default(&prm);
        if (trial % 7 == 6)
            prm.cspace_margin_deg = 2.0;
        qrt_planner_init(&pl, &prm);
        for (k = 0; k < spheres; k++) {
            double rho = test_uniform(0.3, 0.9), phi = test_uniform(-3.1, 3.1);
            n += sphere(cloud + 3 * n, rho * cos(phi), rho * sin(phi),
                        test_uniform(-0.4, 0.6), test_uniform(0.03, 0.15), 16);
        }
        qrt_planner_add_points(&pl, cloud, n);
        qrt_planner_build_mask(&pl);
        s.kind = QRT_TARGET_JOINTS;
        random_joints(s.value);
        if (trial % 2) {
            double p[4][3];
            double q[3];
            random_joints(q);
            ref_fk(q, p);
            g.kind = QRT_TARGET_XYZ;
            g.value[0] = p[3][0];
            g.value[1] = p[3][1];
            g.value[2] = p[3][2];
        } else {
            g.kind = QRT_TARGET_JOINTS;
            random_joints(g.value);
        }
        CHECK(qrt_planner_plan(&pl, &s, &g, &plan) == QRT_OK, "plan");
        if (plan.status != QRT_STATUS_OK)
            continue;
        solved++;
        CHECK(plan.n_waypoints >= 2, "waypoints %d", plan.n_waypoints);
        CHECK(qrt_arm_joint_distance(&prm.arm, plan.waypoints_deg[0], s.value) <
                  1e-9,
              "path does not start at the start");
        {
            double c = path_clearance(&plan, cloud, n, radius);
            CHECK(c >= 0.0, "trial %d: path clearance %g", trial, c);
        }
        CHECK(plan.cost_deg <= plan.lattice_cost_deg + 1e-6,
              "simplified %g longer than lattice %g", plan.cost_deg,
              plan.lattice_cost_deg);
    }
    printf("random scenes solved: %d of 150\n", solved);
    CHECK(solved > test_count(150) / 2, "only %d solved", solved);
}

/* The paper's Table 4 situation: alpha from -100 to 100 across +-180. */
static void test_table4(void)
{
    struct qrt_params prm;
    struct qrt_target s = {
        QRT_TARGET_JOINTS, {-100, 0, 0}, {QRT_FACING_ANY, QRT_ELBOW_ANY}};
    struct qrt_target g = {
        QRT_TARGET_JOINTS, {100, 0, 0}, {QRT_FACING_ANY, QRT_ELBOW_ANY}};
    struct qrt_plan plan;
    long n = sphere(cloud, -0.6, 0.0, 0.05, 0.1, 38);
    double radius[3] = {0.03, 0.03, 0.03};
    int i, crosses = 0;
    qrt_params_default(&prm);
    qrt_planner_init(&pl, &prm);
    qrt_planner_add_points(&pl, cloud, n);
    qrt_planner_build_mask(&pl);
    CHECK(qrt_planner_plan(&pl, &s, &g, &plan) == QRT_OK, "plan");
    CHECK(plan.status == QRT_STATUS_OK, "status %s",
          qrt_plan_status_name(plan.status));
    for (i = 1; i < plan.n_waypoints; i++)
        crosses += fabs(plan.waypoints_deg[i][0] -
                        plan.waypoints_deg[i - 1][0]) > 180.0;
    CHECK(crosses == 1, "path should cross +-180 once, crossed %d", crosses);
    CHECK(path_clearance(&plan, cloud, n, radius) >= 0.0, "table 4 path safe");
}

static void test_statuses(void)
{
    struct qrt_params prm;
    struct qrt_target s = {
        QRT_TARGET_JOINTS, {0, 0, 0}, {QRT_FACING_ANY, QRT_ELBOW_ANY}};
    struct qrt_target g = {
        QRT_TARGET_JOINTS, {90, 0, 0}, {QRT_FACING_ANY, QRT_ELBOW_ANY}};
    struct qrt_target far = {
        QRT_TARGET_XYZ, {1.5, 0, 0}, {QRT_FACING_ANY, QRT_ELBOW_ANY}};
    struct qrt_target bad = {
        QRT_TARGET_JOINTS, {0, -60, 0}, {QRT_FACING_ANY, QRT_ELBOW_ANY}};
    struct qrt_target nan_t = {
        QRT_TARGET_XYZ, {NAN, 0, 0}, {QRT_FACING_ANY, QRT_ELBOW_ANY}};
    struct qrt_plan plan;
    double on_tip[3] = {0.96, 0.0, 0.0};
    long n;
    qrt_params_default(&prm);
    qrt_planner_init(&pl, &prm);
    CHECK(qrt_planner_plan(&pl, &s, &g, &plan) == QRT_E_INVALID,
          "mask not built yet");
    qrt_planner_build_mask(&pl);
    CHECK(qrt_planner_plan(&pl, &s, &g, &plan) == QRT_OK &&
              plan.status == QRT_STATUS_OK && plan.n_waypoints == 2,
          "free space: straight line, %d waypoints", plan.n_waypoints);
    CHECK(fabs(plan.cost_deg - 90.0) < 1e-9, "cost %g", plan.cost_deg);
    CHECK(qrt_planner_plan(&pl, &s, &far, &plan) == QRT_OK &&
              plan.status == QRT_STATUS_UNREACHABLE,
          "unreachable: %s", qrt_plan_status_name(plan.status));
    CHECK(qrt_planner_plan(&pl, &s, &bad, &plan) == QRT_E_LIMITS, "limits");
    CHECK(qrt_planner_plan(&pl, &s, &nan_t, &plan) == QRT_E_INVALID, "nan");
    qrt_planner_add_points(&pl, on_tip, 1);
    qrt_planner_build_mask(&pl);
    CHECK(qrt_planner_plan(&pl, &s, &g, &plan) == QRT_OK &&
              plan.status == QRT_STATUS_START_BLOCKED,
          "start blocked: %s", qrt_plan_status_name(plan.status));
    CHECK(qrt_planner_plan(&pl, &g, &s, &plan) == QRT_OK &&
              plan.status == QRT_STATUS_GOAL_BLOCKED,
          "goal blocked: %s", qrt_plan_status_name(plan.status));
    /* two small walls across link 1's circle at alpha 45 and 135: link 1
     * cannot pass them, so alpha 90 and alpha 0 are not connected */
    qrt_planner_clear_points(&pl);
    {
        int i, j, w;
        n = 0;
        for (w = 0; w < 2; w++)
            for (i = 0; i <= 10; i++)
                for (j = 0; j <= 8; j++) {
                    double r = 0.05 + 0.01 * i, a = w ? 2.35619449 : 0.785398;
                    cloud[3 * n] = r * cos(a);
                    cloud[3 * n + 1] = r * sin(a);
                    cloud[3 * n + 2] = -0.04 + 0.01 * j;
                    n++;
                }
        qrt_planner_add_points(&pl, cloud, n);
    }
    s.value[0] = 90.0;
    g.value[0] = 0.0;
    qrt_planner_build_mask(&pl);
    CHECK(qrt_planner_plan(&pl, &s, &g, &plan) == QRT_OK &&
              plan.status == QRT_STATUS_NO_PATH,
          "walled in: %s (%s)", qrt_plan_status_name(plan.status), plan.detail);
}

/* Starts 1-20 mm from an obstacle: their own lattice cell is blocked, so
 * the join to the lattice must be proved against the points themselves
 * (conservative advancement). The paths must still be safe. */
static void test_starts_near_obstacles(void)
{
    struct qrt_params prm;
    double radius[3] = {0.03, 0.03, 0.03};
    int trial, tried = 0, solved = 0, exact_joins = 0;
    long n = sphere(cloud, 0.55, 0.0, 0.1, 0.12, 30);
    qrt_params_default(&prm);
    qrt_planner_init(&pl, &prm);
    qrt_planner_add_points(&pl, cloud, n);
    qrt_planner_build_mask(&pl);
    for (trial = 0; trial < 4000 && tried < test_count(60); trial++) {
        struct qrt_target s = {
            QRT_TARGET_JOINTS, {0, 0, 0}, {QRT_FACING_ANY, QRT_ELBOW_ANY}};
        struct qrt_target g = {QRT_TARGET_JOINTS,
                               {-150, 30, -20},
                               {QRT_FACING_ANY, QRT_ELBOW_ANY}};
        struct qrt_plan plan;
        double c;
        s.value[0] = test_uniform(-40, 40);
        s.value[1] = test_uniform(-40, 60);
        s.value[2] = test_uniform(-90, 90);
        c = ref_clearance(s.value, cloud, n, radius);
        if (c <= 0.001 || c > 0.02)
            continue;
        tried++;
        CHECK(qrt_planner_plan(&pl, &s, &g, &plan) == QRT_OK, "plan");
        if (plan.status != QRT_STATUS_OK)
            continue;
        solved++;
        {
            int ijk[3], j;
            for (j = 0; j < 3; j++)
                ijk[j] = (int)floor((s.value[j] - pl.mask.lat.lo_deg[j]) /
                                        pl.mask.lat.grid_deg +
                                    0.5);
            ijk[0] %= pl.mask.lat.n[0];
            exact_joins += qrt_mask_blocked(&pl.mask, ijk);
        }
        CHECK(path_clearance(&plan, cloud, n, radius) >= 0.0,
              "near-obstacle start (%g %g %g): path collides", s.value[0],
              s.value[1], s.value[2]);
    }
    printf("starts 1-20 mm from the sphere: %d tried, %d planned, %d of them "
           "joined from a blocked cell\n",
           tried, solved, exact_joins);
    CHECK(tried == test_count(60) && solved > tried / 6 &&
              exact_joins > tried / 12,
          "near-obstacle starts: %d tried, %d solved, %d exact joins", tried,
          solved, exact_joins);
}

/* The ABI guard (planner.h, struct qrt_abi): a caller whose build differs
 * from the library's is refused before its planner is touched, and told in
 * one sentence which settings differ, with both values. */
static void test_abi_guard(void)
{
    struct qrt_params prm;
    struct qrt_abi abi = qrt_abi_here(), worst;
    char why[QRT_ABI_MESSAGE_LEN], expect[QRT_ABI_MESSAGE_LEN], tiny[8],
        lmin[24];
    qrt_params_default(&prm);
    snprintf(lmin, sizeof lmin, "%ld", LONG_MIN);
    CHECK(qrt_abi_check(&abi, why, sizeof why) == QRT_OK && why[0] == '\0',
          "same build: '%s'", why);
    CHECK(qrt_abi_message(why, sizeof why)[0] == '\0', "message '%s'", why);

    abi.grid_deg_min = QRT_GRID_DEG_MIN == 10 ? 5 : 10;
    abi.max_points = QRT_MAX_POINTS == 1024 ? 2048 : 1024;
    pl.mask_state = QRT_MASK_WHOLE; /* init would set QRT_MASK_NONE */
    CHECK(qrt_planner_init_abi(&pl, &prm, &abi) == QRT_E_ABI &&
              qrt_planner_mask_state(&pl) == QRT_MASK_WHOLE,
          "other settings refused, planner untouched");
    CHECK(qrt_abi_check(&abi, NULL, 0) == QRT_E_ABI, "verdict alone");
    CHECK(qrt_abi_check(&abi, why, sizeof why) == QRT_E_ABI, "settings");
    snprintf(expect, sizeof expect,
             "the caller was built with QRT_GRID_DEG_MIN %ld, the library "
             "with %d; with QRT_MAX_POINTS %ld, the library with %ld",
             abi.grid_deg_min, QRT_GRID_DEG_MIN, abi.max_points,
             (long)QRT_MAX_POINTS);
    CHECK(strcmp(why, expect) == 0, "message '%s'", why);
    CHECK(qrt_abi_check(&abi, tiny, sizeof tiny) == QRT_E_ABI &&
              strcmp(tiny, "the cal") == 0,
          "cut short: '%s'", tiny);

    /* QRT_MAX_WAYPOINTS sizes struct qrt_plan, not the planner */
    abi = qrt_abi_here();
    abi.max_waypoints = 64;
    CHECK(qrt_planner_init_abi(&pl, &prm, &abi) == QRT_E_ABI, "waypoints");

    abi = qrt_abi_here();
    abi.planner_bytes += 8;
    qrt_abi_check(&abi, why, sizeof why);
    snprintf(expect, sizeof expect,
             "the caller was built with sizeof(struct qrt_planner) %ld, the "
             "library with %ld (the same settings: another compiler or ABI "
             "option)",
             abi.planner_bytes, (long)sizeof(struct qrt_planner));
    CHECK(strcmp(why, expect) == 0, "message '%s'", why);

    abi = qrt_abi_here();
    abi.abi_bytes -= (long)sizeof(long);
    CHECK(qrt_abi_check(&abi, why, sizeof why) == QRT_E_ABI &&
              strstr(why, "another qrtplan version") != NULL,
          "message '%s'", why);

    /* the longest sentences fit QRT_ABI_MESSAGE_LEN whole */
    worst = qrt_abi_here();
    worst.grid_deg_min = worst.max_points = worst.max_waypoints =
        worst.goal_region_nodes = worst.lazy_index_after = LONG_MIN;
    qrt_abi_check(&worst, why, sizeof why);
    CHECK(strlen(why) + 1 < sizeof why && strstr(why, lmin) &&
              strstr(why, "QRT_LAZY_INDEX_AFTER"),
          "longest settings sentence cut: '%s'", why);
    worst = qrt_abi_here();
    worst.planner_bytes = worst.plan_bytes = worst.target_bytes =
        worst.enum_bytes = LONG_MIN;
    qrt_abi_check(&worst, why, sizeof why);
    CHECK(strlen(why) + 1 < sizeof why && strstr(why, "ABI option)") &&
              strstr(why, "sizeof(struct qrt_target)"),
          "longest sizes sentence cut: '%s'", why);

    CHECK(strstr(qrt_err_name(QRT_E_ABI), "settings") != NULL, "err name");
    CHECK(qrt_planner_init(&pl, &prm) == QRT_OK &&
              qrt_planner_mask_state(&pl) == QRT_MASK_NONE,
          "the caller's own build is the library's");
}

int main(void)
{
    test_seed(2024);
    test_abi_guard();
    test_statuses();
    test_starts_near_obstacles();
    test_table4();
    test_random_scenes();
    return test_done("test_planner");
}
