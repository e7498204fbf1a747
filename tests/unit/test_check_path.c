/* qrt_planner_check_path: every path the planner returns checks free on
 * the same mask; a point dropped onto the arm somewhere along a segment
 * makes that segment (or an earlier one) blocked after the next build;
 * bad input is refused. qrt_planner_check_path_now, which builds only the
 * rows the path passes through: never free where the whole mask is not,
 * catches the same point before any build, agrees with the whole mask on
 * (nearly) every path, and leaves a mask the planner refuses. */
#include <math.h>

#include "check.h"
#include "qrtplan/qrtplan.h"

static struct qrt_planner pl;
static struct qrt_plan plan;

/* The joints part way (t) along the motion from waypoint seg of the plan
 * (alpha the short way round, as the planner moves). */
static void along(const struct qrt_plan *pn, int seg, double t, double q[3])
{
    int k;
    for (k = 0; k < 3; k++) {
        double d = pn->waypoints_deg[seg + 1][k] - pn->waypoints_deg[seg][k];
        if (k == 0)
            d = d > 180 ? d - 360 : d <= -180 ? d + 360 : d;
        q[k] = pn->waypoints_deg[seg][k] + t * d;
    }
    if (q[0] > 180)
        q[0] -= 360;
    if (q[0] <= -180)
        q[0] += 360;
}

/* Paths of the sampled fallback, which run near points for long, checked
 * as the daemon's guard checks the path being executed (the points loaded
 * anew, then qrt_planner_check_path_now, whose advancement passes over far
 * blocks of the table in Morton order): free, as the planner proved them,
 * and free on the whole mask too (advancement without the boxes); a point
 * on the forearm part way along one segment is caught there or earlier by
 * both. Clouds of BALLS balls on a 20 degree lattice, whose cells close
 * passages that exist. */
#define BALLS 30
#define BALL_POINTS 30
#define N_CLOUD (BALLS * BALL_POINTS)
static void sampled_paths(void)
{
    static double cloud[3 * (N_CLOUD + 1)];
    long trial, sampled = 0, caught = 0;
    for (trial = 0; trial < test_count(120); trial++) {
        struct qrt_params prm;
        struct qrt_target s = {
            QRT_TARGET_JOINTS, {0, 0, 0}, {QRT_FACING_ANY, QRT_ELBOW_ANY}};
        struct qrt_target g = s;
        double q[3], p[4][3];
        int i, k, seg, now, blocked;
        for (i = 0; i < BALLS; i++) {
            double c[3], r = test_uniform(0.06, 0.16);
            double a = test_uniform(-3.14159, 3.14159),
                   d = test_uniform(0.3, 0.8);
            c[0] = d * cos(a);
            c[1] = d * sin(a);
            c[2] = test_uniform(-0.2, 0.7);
            for (k = 0; k < BALL_POINTS; k++) {
                double u = test_uniform(-1, 1), v = test_uniform(0, 6.28318);
                double w = sqrt(1 - u * u);
                double *pt = cloud + 3 * (BALL_POINTS * i + k);
                pt[0] = c[0] + r * w * cos(v);
                pt[1] = c[1] + r * w * sin(v);
                pt[2] = c[2] + r * u;
            }
        }
        for (k = 0; k < 3; k++) { /* within the default limits */
            s.value[k] = test_uniform(k == 1 ? -30 : -170, k == 2 ? 130 : 170);
            g.value[k] = test_uniform(k == 1 ? -30 : -170, k == 2 ? 130 : 170);
        }
        qrt_params_default(&prm);
        prm.grid_deg = 20.0;
        if (qrt_planner_init(&pl, &prm) != QRT_OK)
            continue;
        qrt_planner_add_points(&pl, cloud, N_CLOUD);
        if (qrt_planner_plan_now(&pl, &s, &g, &plan) != QRT_OK ||
            plan.status != QRT_STATUS_OK || plan.sampled_nodes == 0 ||
            plan.n_waypoints < 2)
            continue;
        sampled++;
        qrt_planner_clear_points(&pl);
        qrt_planner_add_points(&pl, cloud, N_CLOUD);
        CHECK(qrt_planner_check_path_now(&pl,
                                         (const double(*)[3])plan.waypoints_deg,
                                         plan.n_waypoints, &now) == QRT_OK &&
                  now == -1,
              "trial %ld: the sampled path is blocked at %d by the guard's "
              "check",
              trial, now);
        qrt_planner_build_mask(&pl);
        CHECK(qrt_planner_check_path(&pl,
                                     (const double(*)[3])plan.waypoints_deg,
                                     plan.n_waypoints, &blocked) == QRT_OK &&
                  blocked == -1,
              "trial %ld: the sampled path is blocked at %d on the whole mask",
              trial, blocked);
        seg = (int)test_uniform(0, plan.n_waypoints - 1);
        along(&plan, seg, test_uniform(0.2, 0.8), q);
        qrt_arm_fk(&prm.arm, q, p);
        for (k = 0; k < 3; k++)
            cloud[3 * N_CLOUD + k] = 0.5 * (p[2][k] + p[3][k]);
        qrt_planner_clear_points(&pl);
        qrt_planner_add_points(&pl, cloud, N_CLOUD + 1);
        CHECK(qrt_planner_check_path_now(&pl,
                                         (const double(*)[3])plan.waypoints_deg,
                                         plan.n_waypoints, &now) == QRT_OK &&
                  now >= 0 && now <= seg,
              "trial %ld: a point on segment %d, the guard's check says %d",
              trial, seg, now);
        qrt_planner_build_mask(&pl);
        CHECK(qrt_planner_check_path(&pl,
                                     (const double(*)[3])plan.waypoints_deg,
                                     plan.n_waypoints, &blocked) == QRT_OK &&
                  blocked >= 0 && blocked <= seg,
              "trial %ld: a point on segment %d, the whole mask says %d", trial,
              seg, blocked);
        caught += now >= 0;
    }
    printf("sampled paths checked: %ld, obstacles on them caught: %ld\n",
           sampled, caught);
    CHECK(sampled >= test_count(120) / 20, "only %ld sampled paths", sampled);
}

int main(void)
{
    long trial, planned = 0, caught = 0, agree = 0, straight_ok = 0,
                straight_full = 0;
    static struct qrt_plan plan2;
    test_seed(9191);
    for (trial = 0; trial < test_count(60); trial++) {
        struct qrt_params prm;
        struct qrt_target s = {
            QRT_TARGET_JOINTS, {0, 0, 0}, {QRT_FACING_ANY, QRT_ELBOW_ANY}};
        struct qrt_target g = {
            QRT_TARGET_JOINTS, {0, 0, 0}, {QRT_FACING_ANY, QRT_ELBOW_ANY}};
        double cloud[3 * 40], q[3], p[4][3], t;
        int i, seg, blocked, now, straight, rc;
        for (i = 0; i < 40; i++) {
            double a = test_uniform(-3.14159, 3.14159);
            cloud[3 * i] = 0.6 * cos(a) + test_uniform(-0.05, 0.05);
            cloud[3 * i + 1] = 0.6 * sin(a) + test_uniform(-0.05, 0.05);
            cloud[3 * i + 2] = test_uniform(0.3, 0.5);
        }
        s.value[0] = test_uniform(-170, 170);
        g.value[0] = test_uniform(-170, 170);
        g.value[1] = test_uniform(-30, 60);
        g.value[2] = test_uniform(-60, 60);
        qrt_params_default(&prm);
        qrt_planner_init(&pl, &prm);
        qrt_planner_add_points(&pl, cloud, 40);
        /* the straight motion before any mask: proved only where the whole
         * mask proves it too, and then the same plan */
        rc = qrt_planner_plan_straight(&pl, &s, &g, &plan2, &straight);
        CHECK(rc == QRT_OK && (straight == 0 || straight == 1),
              "plan_straight returned %d, straight %d", rc, straight);
        qrt_planner_build_mask(&pl);
        if (qrt_planner_plan(&pl, &s, &g, &plan) == QRT_OK) {
            int full = plan.status == QRT_STATUS_OK && plan.n_waypoints == 2 &&
                       plan.nodes_expanded == 0;
            CHECK(!straight || full,
                  "trial %ld: straight before the mask, not after it", trial);
            CHECK(!straight || (plan2.n_waypoints == 2 &&
                                fabs(plan2.cost_deg - plan.cost_deg) < 1e-9 &&
                                plan2.cells_blocked == -1),
                  "trial %ld: the straight plans differ", trial);
            straight_ok += straight;
            straight_full += full;
        }
        if (qrt_planner_plan(&pl, &s, &g, &plan) != QRT_OK ||
            plan.status != QRT_STATUS_OK || plan.n_waypoints < 2)
            continue;
        planned++;
        CHECK(qrt_planner_check_path_now(&pl,
                                         (const double(*)[3])plan.waypoints_deg,
                                         plan.n_waypoints, &now) == QRT_OK,
              "check_path_now refused a planned path");
        agree += now == -1;
        CHECK(qrt_planner_plan(&pl, &s, &g, &plan2) == QRT_E_INVALID,
              "planned on the partial mask check_path_now leaves");
        qrt_planner_build_mask(&pl);
        CHECK(qrt_planner_check_path(&pl,
                                     (const double(*)[3])plan.waypoints_deg,
                                     plan.n_waypoints, &blocked) == QRT_OK,
              "check refused a planned path");
        CHECK(blocked == -1, "trial %ld: planned path blocked at %d", trial,
              blocked);
        /* a point on the forearm's middle, part way along one segment */
        seg = (int)test_uniform(0, plan.n_waypoints - 1);
        t = test_uniform(0.2, 0.8);
        along(&plan, seg, t, q);
        qrt_arm_fk(&prm.arm, q, p);
        {
            double hit[3] = {0.5 * (p[2][0] + p[3][0]),
                             0.5 * (p[2][1] + p[3][1]),
                             0.5 * (p[2][2] + p[3][2])};
            qrt_planner_add_points(&pl, hit, 1);
        }
        CHECK(qrt_planner_check_path_now(&pl,
                                         (const double(*)[3])plan.waypoints_deg,
                                         plan.n_waypoints, &now) == QRT_OK,
              "check_path_now refused");
        CHECK(now >= 0 && now <= seg,
              "trial %ld: a point on segment %d, check_path_now says %d", trial,
              seg, now);
        qrt_planner_build_mask(&pl);
        CHECK(qrt_planner_check_path(&pl,
                                     (const double(*)[3])plan.waypoints_deg,
                                     plan.n_waypoints, &blocked) == QRT_OK,
              "check refused");
        CHECK(blocked >= 0 && blocked <= seg,
              "trial %ld: a point on segment %d, check says %d", trial, seg,
              blocked);
        /* the partial build blocks at least what the whole one does */
        CHECK(blocked < 0 || now <= blocked,
              "trial %ld: check_path_now free up to %d, the mask blocks %d",
              trial, now, blocked);
        caught += blocked >= 0;
    }
    CHECK(planned >= test_count(60) / 2, "only %ld of the scenes planned",
          planned);
    printf("paths checked: %ld, obstacles on them caught: %ld; "
           "check_path_now free on %ld of the planned paths\n",
           planned, caught, agree);
    printf("straight motions: %ld proved before the mask, %ld with it\n",
           straight_ok, straight_full);
    CHECK(straight_ok == straight_full && straight_full > 0,
          "plan_straight proved %ld of the %ld straight plans", straight_ok,
          straight_full);
    CHECK(agree * 100 >= planned * 95,
          "check_path_now proved only %ld of %ld planned paths free", agree,
          planned);
    {
        double bad[2][3] = {{0, 0, 0}, {0, 0, NAN}};
        double out[2][3] = {{0, 0, 0}, {0, 200, 0}};
        int blocked;
        CHECK(qrt_planner_check_path(&pl, (const double(*)[3])bad, 2,
                                     &blocked) == QRT_E_INVALID,
              "NaN accepted");
        CHECK(qrt_planner_check_path(&pl, (const double(*)[3])out, 2,
                                     &blocked) == QRT_E_LIMITS,
              "sigma 200 accepted");
        CHECK(qrt_planner_check_path(&pl, (const double(*)[3])out, 0,
                                     &blocked) == QRT_E_INVALID,
              "n = 0 accepted");
        CHECK(qrt_planner_check_path_now(&pl, (const double(*)[3])bad, 2,
                                         &blocked) == QRT_E_INVALID,
              "check_path_now accepted NaN");
        CHECK(qrt_planner_check_path_now(&pl, (const double(*)[3])out, 2,
                                         &blocked) == QRT_E_LIMITS,
              "check_path_now accepted sigma 200");
        qrt_planner_add_points(&pl, bad[0], 1);
        CHECK(qrt_planner_check_path(&pl, (const double(*)[3])out, 1,
                                     &blocked) == QRT_E_INVALID,
              "a stale mask accepted");
    }
    sampled_paths();
    return test_done("test_check_path");
}
