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
        CHECK(fabs(pts.x[i] - xyz[3 * i]) < 1e-7 &&
                  fabs(pts.y[i] - xyz[3 * i + 1]) < 1e-7 &&
                  fabs(pts.z[i] - xyz[3 * i + 2]) < 1e-7,
              "stored exactly");
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
            double d = pow(pts.x[j] - xyz[3 * i], 2) +
                       pow(pts.y[j] - xyz[3 * i + 1], 2) +
                       pow(pts.z[j] - xyz[3 * i + 2], 2);
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

/* Every way a coordinate can be unusable, in every axis of a point in the
 * middle of a batch, whether the point's other coordinates are within reach
 * or far beyond it: refused whole, nothing counted, and the point stored
 * before the batch kept as it was. Finite extremes (1e308, the smallest
 * subnormal) are usable, far ones ignored. */
static void test_each_bad_coordinate(void)
{
    const double bad[4] = {NAN, -NAN, INFINITY, -INFINITY};
    const double first[3] = {0.1, -0.2, 0.3};
    double batch[3 * 5];
    double extremes[3 * 4] = {1e308,    0, 0, -1e308, 1e308, -1e308,
                              4.9e-324, 0, 0, 0.2,    -0.3,  0.1};
    int v, k, i, far;
    qrt_points_reset(&pts, 1.0);
    CHECK(qrt_points_add(&pts, first, 1) == QRT_OK, "first point");
    for (v = 0; v < 4; v++)
        for (k = 0; k < 3; k++)
            for (far = 0; far < 2; far++) {
                for (i = 0; i < 15; i++)
                    batch[i] = 0.01 * (double)(i + 1);
                if (far)
                    for (i = 0; i < 3; i++)
                        batch[3 * 2 + i] = 1e308;
                batch[3 * 2 + k] = bad[v];
                CHECK(qrt_points_add(&pts, batch, 5) == QRT_E_INVALID,
                      "value %d in axis %d (far %d) refused", v, k, far);
                CHECK(pts.count == 1 && pts.received == 1 &&
                          pts.ignored_far == 0,
                      "value %d axis %d far %d: nothing counted (%ld %ld %ld)",
                      v, k, far, pts.count, pts.received, pts.ignored_far);
                CHECK(pts.x[0] == (float)first[0] &&
                          pts.y[0] == (float)first[1] &&
                          pts.z[0] == (float)first[2],
                      "value %d axis %d far %d: stored point kept", v, k, far);
            }
    qrt_points_reset(&pts, 1.0);
    CHECK(qrt_points_add(&pts, extremes, 4) == QRT_OK, "finite extremes");
    CHECK(pts.count == 2 && pts.received == 4 && pts.ignored_far == 2,
          "extremes: %ld stored, %ld received, %ld far", pts.count,
          pts.received, pts.ignored_far);
}

/* The counters mean the same whether a batch fits the exact table or
 * tips it into voxels: received counts every point passed, ignored_far
 * those beyond reach, and the rest are stored (or merged into a voxel). */
static void test_counters_both_ways(void)
{
    static double xyz[3 * 2 * QRT_MAX_POINTS];
    long i, n = 2 * QRT_MAX_POINTS, far = 0;
    qrt_points_reset(&pts, 1.0);
    for (i = 0; i < n; i++) {
        int is_far = (i % 7) == 3;
        xyz[3 * i] = is_far ? 1.5 : test_uniform(-0.5, 0.5);
        xyz[3 * i + 1] = test_uniform(-0.5, 0.5);
        xyz[3 * i + 2] = test_uniform(-0.2, 0.2);
        far += is_far;
    }
    CHECK(qrt_points_add(&pts, xyz, 1000) == QRT_OK, "exact batch");
    CHECK(pts.received == 1000 && pts.ignored_far == 143 &&
              pts.count == 1000 - 143 && pts.voxel_m == 0.0,
          "exact: %ld %ld %ld", pts.received, pts.ignored_far, pts.count);
    CHECK(qrt_points_add(&pts, xyz + 3 * 1000, n - 1000) == QRT_OK,
          "overflowing batch");
    CHECK(pts.received == n && pts.ignored_far == far && pts.voxel_m > 0.0,
          "voxels: %ld of %ld received, %ld of %ld far", pts.received, n,
          pts.ignored_far, far);
}

/* A point at distance r from the base in a random direction. */
static void at_distance(double r, double p[3])
{
    double len;
    int k;
    do {
        for (k = 0; k < 3; k++)
            p[k] = test_uniform(-1.0, 1.0);
        len = sqrt(p[0] * p[0] + p[1] * p[1] + p[2] * p[2]);
    } while (len < 0.1 || len > 1.0);
    for (k = 0; k < 3; k++)
        p[k] *= r / len;
}

/* Batches long enough to be taken in blocks of 64 points, each block
 * checked whole in float: what is kept, in order, and what is counted far
 * are exactly what the reach test in double says, with many points a hair
 * either side of the reach (where float rounding could say otherwise), far
 * points in some blocks and none in others, and batches that end on a
 * block's edge or not. A bad coordinate at a block's first or last point,
 * in a later block or in the last, shorter one refuses the batch whole. */
static void test_blocks_exact(void)
{
    static double xyz[3 * 1000];
    const long sizes[6] = {64, 65, 127, 128, 300, 1000};
    const long bad_at[6] = {0, 63, 64, 127, 129, 299};
    const double reach = 0.9;
    int trial;
    for (trial = 0; trial < 100; trial++) {
        long n = sizes[trial % 6], i, kept = 0, far = 0;
        /* 0: only inside; 1: hairs either side; 2: far points; 3: both;
         * 4: one point in each block beyond reach by 1e-12 to 1e-8 of it,
         * which float rounding alone cannot tell from the reach */
        int mix = trial % 5, v = trial % 3;
        double keep;
        for (i = 0; i < n; i++) {
            double *p = xyz + 3 * i, u = test_uniform(0.0, 1.0), r;
            /* some blocks get none but inside points */
            int plain = (i / 64) % 3 == 1 || mix == 0;
            if (mix == 4 && i % 64 == 17)
                r = reach * (1.0 + pow(10.0, test_uniform(-12, -8)));
            else if (!plain && (mix == 1 || mix == 3) && u < 0.3)
                r = reach * (1.0 + (u < 0.15 ? 1.0 : -1.0) *
                                       pow(10.0, test_uniform(-12, -5)));
            else if (!plain && (mix == 2 || mix == 3) && u > 0.9)
                r = test_uniform(0.91, 5.0);
            else
                r = test_uniform(0.0, 0.899);
            at_distance(r, p);
        }
        qrt_points_reset(&pts, reach);
        CHECK(qrt_points_add(&pts, xyz, n) == QRT_OK, "batch of %ld", n);
        for (i = 0; i < n; i++) {
            const double *p = xyz + 3 * i;
            if (p[0] * p[0] + p[1] * p[1] + p[2] * p[2] <= reach * reach) {
                CHECK(kept < pts.count && pts.x[kept] == (float)p[0] &&
                          pts.y[kept] == (float)p[1] &&
                          pts.z[kept] == (float)p[2],
                      "trial %d: point %ld is stored %ld", trial, i, kept);
                kept++;
            } else {
                far++;
            }
        }
        CHECK(pts.count == kept && pts.ignored_far == far && pts.received == n,
              "trial %d: %ld stored (%ld in reach), %ld far (%ld)", trial,
              pts.count, kept, pts.ignored_far, far);
        /* now a bad coordinate: nothing changes */
        keep = xyz[3 * bad_at[trial % 6] + v];
        xyz[3 * bad_at[trial % 6] + v] = v == 0   ? NAN
                                         : v == 1 ? INFINITY
                                                  : -INFINITY;
        CHECK(qrt_points_add(&pts, xyz, n) == QRT_E_INVALID,
              "trial %d: bad value at %ld refused", trial, bad_at[trial % 6]);
        CHECK(pts.count == kept && pts.received == n,
              "trial %d: nothing counted from the bad batch", trial);
        xyz[3 * bad_at[trial % 6] + v] = keep;
    }
}

/* A long arm reaches so much space that not even 64 mm voxels fit: the
 * planner must refuse with QRT_STATUS_CAPACITY, never overflow. */
static void test_capacity(void)
{
    static double xyz[3 * 4096];
    struct qrt_params prm;
    struct qrt_target s = {
        QRT_TARGET_JOINTS, {0, 0, 0}, {QRT_FACING_ANY, QRT_ELBOW_ANY}};
    struct qrt_target g = {
        QRT_TARGET_JOINTS, {90, 0, 0}, {QRT_FACING_ANY, QRT_ELBOW_ANY}};
    struct qrt_plan plan;
    int batch, i;
    qrt_params_default(&prm);
    prm.arm.link_m[1] = 3.0;
    prm.arm.link_m[2] = 3.0;
    CHECK(qrt_planner_init(&pl, &prm) == QRT_OK, "init");
    /* four points a table entry: over 1.3 million voxels of 64 mm in the
     * 7 m cube, so most points take one of their own */
    for (batch = 0; batch < 4 * QRT_MAX_POINTS / 4096 + 1; batch++) {
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

/* Entries by voxel, for test_merged_shapes: (key, entry) sorted. */
struct keyed {
    long v[3];
    long entry;
};

static int by_voxel(const void *a, const void *b)
{
    const struct keyed *p = (const struct keyed *)a,
                       *q = (const struct keyed *)b;
    int k;
    for (k = 0; k < 3; k++)
        if (p->v[k] != q->v[k])
            return p->v[k] < q->v[k] ? -1 : 1;
    return 0;
}

/* Every point merged into an entry lies inside the entry's box and inside
 * the ball of the inflation round its stored position; checked for every
 * point, not by the table's own lookup: the test finds each point's entry
 * by voxel among the entries sorted by the voxel of their stored position.
 * Returns the inflation over the voxel's half-diagonal (the bound the
 * entries had as voxel centres, which it must not pass). */
static double check_merged(const double *xyz, long n, const char *cloud)
{
    static struct keyed keys[QRT_MAX_POINTS];
    long i, outside_box = 0, outside_ball = 0, lost = 0;
    double e, step, infl, worst = 0.0;
    qrt_points_reset(&pts, 2.0);
    CHECK(qrt_points_add(&pts, xyz, n) == QRT_OK, "%s: add", cloud);
    CHECK(pts.voxel_m > 0.0 && pts.dropped == 0,
          "%s: merged, voxel %g, dropped %ld", cloud, pts.voxel_m, pts.dropped);
    e = pts.voxel_m;
    step = e / QRT_VOXEL_BOX_STEPS;
    infl = qrt_points_inflation_m(&pts);
    for (i = 0; i < pts.count; i++) {
        double c[3];
        int k;
        c[0] = pts.x[i];
        c[1] = pts.y[i];
        c[2] = pts.z[i];
        for (k = 0; k < 3; k++)
            keys[i].v[k] = (long)floor(c[k] / e);
        keys[i].entry = i;
    }
    qsort(keys, (size_t)pts.count, sizeof keys[0], by_voxel);
    for (i = 0; i < n; i++) {
        /* the point as the table took it: exact while the table was, as
         * a float; merged, as given (the inflation holds the difference) */
        double q[2][3], d2 = 0.0;
        int k, form, inside = 0;
        long j = -1;
        for (k = 0; k < 3; k++) {
            /* volatile: GCC 12 at -O3 dropped the rounding to float when
             * it vectorised this loop, and the float form is the one the
             * table kept while it was exact */
            volatile float f = (float)xyz[3 * i + k];
            q[0][k] = xyz[3 * i + k];
            q[1][k] = f;
        }
        for (form = 0; form < 2 && !inside; form++) {
            struct keyed want, *got;
            for (k = 0; k < 3; k++)
                want.v[k] = (long)floor(q[form][k] / e);
            got = (struct keyed *)bsearch(&want, keys, (size_t)pts.count,
                                          sizeof keys[0], by_voxel);
            if (!got)
                continue;
            j = got->entry;
            inside = 1;
            for (k = 0; k < 3; k++) {
                double off = q[form][k] - (double)want.v[k] * e;
                if (off < pts.box_lo[k][j] * step - 1e-12 ||
                    off > pts.box_hi[k][j] * step + 1e-12)
                    inside = 0;
            }
        }
        if (j < 0) {
            lost++;
            continue;
        }
        if (!inside)
            outside_box++;
        d2 = pow(q[0][0] - pts.x[j], 2) + pow(q[0][1] - pts.y[j], 2) +
             pow(q[0][2] - pts.z[j], 2);
        if (sqrt(d2) > infl)
            outside_ball++;
        worst = fmax(worst, sqrt(d2));
    }
    CHECK(lost == 0, "%s: %ld points with no entry in their voxel", cloud,
          lost);
    CHECK(outside_box == 0, "%s: %ld points outside their entry's box", cloud,
          outside_box);
    CHECK(outside_ball == 0,
          "%s: %ld points farther than the inflation %g from their entry "
          "(worst %g)",
          cloud, outside_ball, infl, worst);
    printf("%s: voxel %.3f m, %ld entries, inflation %.4f m (half-diagonal "
           "%.4f), worst point %.4f m\n",
           cloud, e, pts.count, infl, 0.5 * sqrt(3.0) * e, worst);
    return (infl - 1e-6) / (0.5 * sqrt(3.0) * e);
}

/* A volume and a surface merged over several voxel sizes: every point in
 * its entry's shape; the inflation never passes the voxel's
 * half-diagonal, and on a plane (a scan's surface) is the box's, a face's
 * half-diagonal (1/sqrt(2) of the edge, and the inset's shift), not the
 * cube's. */
static void test_merged_shapes(void)
{
    static double xyz[3 * (QRT_MAX_POINTS + QRT_MAX_POINTS / 2)];
    long i, n = QRT_MAX_POINTS + QRT_MAX_POINTS / 2;
    double ratio;
    for (i = 0; i < n; i++) {
        double *p = xyz + 3 * i;
        p[0] = test_uniform(-0.6, 0.6);
        p[1] = test_uniform(-0.6, 0.6);
        /* half on the plane z = 0.3 + 0.1 x, half in a slab under it */
        p[2] = i % 2 ? 0.3 + 0.1 * p[0] : test_uniform(-0.6, 0.2);
    }
    ratio = check_merged(xyz, n, "slab and tilted plane");
    CHECK(ratio <= 1.0, "inflation over the half-diagonal: %g", ratio);
    /* off the voxel grids' planes, where a box is held an inset inside */
    for (i = 0; i < n; i++)
        xyz[3 * i + 2] = 0.3047;
    ratio = check_merged(xyz, n, "plane z = 0.3047");
    CHECK(ratio < 0.9, "plane: inflation %g of the half-diagonal", ratio);
    /* on the grids' planes: the boxes are held an inset inside their
     * voxels, and the radius must pay for the shift */
    for (i = 0; i < n; i++) { /* dense: boxes as wide as their voxels */
        xyz[3 * i] *= 0.25;
        xyz[3 * i + 1] *= 0.25;
        xyz[3 * i + 2] = 0.3;
    }
    ratio = check_merged(xyz, n, "plane z = 0.3");
    CHECK(ratio <= 1.0, "inflation over the half-diagonal: %g", ratio);
}

int main(void)
{
    test_seed(99);
    test_exact_then_voxels();
    test_merged_shapes();
    test_far_and_bad();
    test_each_bad_coordinate();
    test_counters_both_ways();
    test_blocks_exact();
    test_capacity();
    return test_done("test_points");
}
