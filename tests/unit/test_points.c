/* The point table: exact while it fits, then voxels that only ever grow
 * the obstacles, and a counted drop only when even the coarsest voxels
 * overflow. */
#include "check.h"
#include "qrtplan/qrtplan.h"

static struct qrt_points pts;
static struct qrt_planner pl;

static void test_exact_then_voxels(void)
{
    static double xyz[3 * (QRT_MAX_POINTS + 5000)];
    long i, n = QRT_MAX_POINTS + 5000;
    double worst = 0.0;
    qrt_points_reset(&pts, 2.0);
    for (i = 0; i < 3 * n; i++)
        xyz[i] = test_uniform(-0.5, 0.5);
    CHECK(qrt_points_add(&pts, xyz, QRT_MAX_POINTS) == QRT_OK, "add");
    CHECK(pts.voxel_m == 0.0 && pts.count == QRT_MAX_POINTS, "exact %g %ld",
          pts.voxel_m, pts.count);
    for (i = 0; i < QRT_MAX_POINTS; i++)
        CHECK(fabs(pts.xyz[i][0] - xyz[3 * i]) < 1e-7, "stored exactly");
    CHECK(qrt_points_add(&pts, xyz + 3 * QRT_MAX_POINTS, 5000) == QRT_OK,
          "add more");
    CHECK(pts.voxel_m > 0.0, "switched to voxels");
    CHECK(pts.count <= QRT_MAX_POINTS && pts.dropped == 0, "%ld %ld", pts.count,
          pts.dropped);
    /* every input point is within the inflation of some stored point */
    for (i = 0; i < n; i += 97) {
        double best = 1e30;
        long j;
        for (j = 0; j < pts.count; j++) {
            double d = 0.0;
            int k;
            for (k = 0; k < 3; k++)
                d += pow(pts.xyz[j][k] - xyz[3 * i + k], 2);
            if (d < best)
                best = d;
        }
        worst = fmax(worst, sqrt(best));
    }
    CHECK(worst <= qrt_points_inflation_m(&pts),
          "point %g m from its voxel "
          "centre, inflation %g",
          worst, qrt_points_inflation_m(&pts));
    printf("voxel %.3f m, %ld entries, worst offset %.4f m\n", pts.voxel_m,
           pts.count, worst);
}

static void test_far_and_bad(void)
{
    double far[6] = {5.0, 0, 0, 0.1, 0.1, 0.1};
    double bad[6] = {0.1, 0.1, 0.1, 0.2, NAN, 0.0};
    double inf[3] = {INFINITY, 0, 0};
    qrt_points_reset(&pts, 1.0);
    CHECK(qrt_points_add(&pts, far, 2) == QRT_OK, "far ok");
    CHECK(pts.count == 1 && pts.ignored_far == 1, "far ignored");
    CHECK(qrt_points_add(&pts, bad, 2) == QRT_E_INVALID, "nan refused");
    CHECK(qrt_points_add(&pts, inf, 1) == QRT_E_INVALID, "inf refused");
    CHECK(pts.count == 1, "nothing added from a bad batch");
    CHECK(qrt_points_add(&pts, NULL, 0) == QRT_OK, "empty batch");
    CHECK(qrt_points_add(&pts, NULL, -1) == QRT_E_INVALID, "negative count");
}

/* A long arm reaches so much space that not even 64 mm voxels fit: the
 * planner must refuse with QRT_STATUS_CAPACITY, never overflow. */
static void test_capacity(void)
{
    static double xyz[3 * 4096];
    struct qrt_params prm;
    struct qrt_target s = {QRT_TARGET_JOINTS, {0, 0, 0}};
    struct qrt_target g = {QRT_TARGET_JOINTS, {90, 0, 0}};
    struct qrt_plan plan;
    int batch, i;
    qrt_params_default(&prm);
    prm.arm.link_m[1] = 3.0;
    prm.arm.link_m[2] = 3.0;
    CHECK(qrt_planner_init(&pl, &prm) == QRT_OK, "init");
    for (batch = 0; batch < 60; batch++) {
        for (i = 0; i < 3 * 4096; i++)
            xyz[i] = test_uniform(-3.5, 3.5);
        qrt_planner_add_points(&pl, xyz, 4096);
    }
    CHECK(pl.points.dropped > 0, "dropped %ld", pl.points.dropped);
    CHECK(pl.points.count == QRT_MAX_POINTS, "table full");
    qrt_planner_build_mask(&pl);
    CHECK(qrt_planner_plan(&pl, &s, &g, &plan) == QRT_OK, "plan call");
    CHECK(plan.status == QRT_STATUS_CAPACITY && plan.points_dropped > 0,
          "status %s", qrt_plan_status_name(plan.status));
}

int main(void)
{
    test_seed(99);
    test_exact_then_voxels();
    test_far_and_bad();
    test_capacity();
    return test_done("test_points");
}
