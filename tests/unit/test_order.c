/* The point table's Morton order (src/core/order.h) and the clearance's
 * block and group boxes (src/core/motion.h): ordering keeps every entry
 * (in voxel mode with its box and its place in the hash), leaves them in
 * Morton order and makes blocks compact; the boxes change no clearance.
 * Uses the core's internal headers. */
#include <string.h>

#include "../../src/core/motion.h"
#include "../../src/core/order.h"
#include "check.h"
#include "qrtplan/qrtplan.h"

#define N_EXACT (QRT_MAX_POINTS < 20000 ? QRT_MAX_POINTS : 20000)

static struct qrt_points pts, copy;
static struct qrt_planner certified, fresh;
static int32_t scratch_a[2 * QRT_MAX_POINTS], scratch_b[2 * QRT_MAX_POINTS];
static float boxes[QRTI_BLOCK_BOXES][6];
static double xyz[3 * 2 * QRT_MAX_POINTS];
static float rows_before[QRT_MAX_POINTS][3], rows_after[QRT_MAX_POINTS][3];

/* The Morton key as the order promises it, bit by bit. */
static unsigned long morton(const struct qrt_points *p, long i)
{
    const float *axis[3];
    unsigned long key = 0;
    int k, b;
    axis[0] = p->x;
    axis[1] = p->y;
    axis[2] = p->z;
    for (k = 0; k < 3; k++) {
        double c =
            ((double)axis[k][i] + p->reach_m) * 1024.0 / (2 * p->reach_m);
        unsigned long cell = c <= 0.0      ? 0
                             : c >= 1023.0 ? 1023
                                           : (unsigned long)c;
        for (b = 0; b < 10; b++)
            key |= ((cell >> b) & 1ul) << (3 * b + k);
    }
    return key;
}

static int row_cmp(const void *a, const void *b)
{
    return memcmp(a, b, 3 * sizeof(float));
}

/* The table's entries as sorted rows, to compare as multisets. */
static void sorted_rows(const struct qrt_points *p, float (*rows)[3])
{
    long i;
    for (i = 0; i < p->count; i++) {
        rows[i][0] = p->x[i];
        rows[i][1] = p->y[i];
        rows[i][2] = p->z[i];
    }
    qsort(rows, (size_t)p->count, sizeof rows[0], row_cmp);
}

static double median_block_diagonal(const struct qrt_points *p)
{
    static double d[QRTI_BLOCK_BOXES];
    long b, blocks = p->count / QRT_CLEARANCE_BLOCK, i, j;
    qrt_points_block_boxes(p, boxes);
    for (b = 0; b < blocks; b++) {
        double s = 0.0;
        for (j = 0; j < 3; j++)
            s += (boxes[b][j + 3] - boxes[b][j]) *
                 (boxes[b][j + 3] - boxes[b][j]);
        d[b] = sqrt(s);
    }
    for (i = 1; i < blocks; i++) /* insertion sort: a few hundred */
        for (j = i; j > 0 && d[j - 1] > d[j]; j--) {
            double t = d[j];
            d[j] = d[j - 1];
            d[j - 1] = t;
        }
    return blocks > 0 ? d[blocks / 2] : 0.0;
}

/* n points on three walls near the arm, in a random order. */
static void wall_points(long n)
{
    long i;
    for (i = 0; i < n; i++) {
        int wall = (int)test_uniform(0, 3);
        double u = test_uniform(-0.6, 0.6), v = test_uniform(-0.3, 0.7);
        double *p = xyz + 3 * i;
        p[0] = wall == 0 ? 0.55 : u;
        p[1] = wall == 1 ? -0.5 : wall == 2 ? 0.5 : u * 0.8;
        p[2] = v;
    }
}

static void check_exact(void)
{
    struct qrt_params prm;
    long i, out_of_order = 0;
    double before, after;
    qrt_params_default(&prm);
    qrt_points_reset(&pts, qrt_arm_reach_m(&prm.arm) + prm.margin_m);
    wall_points(N_EXACT);
    CHECK(qrt_points_add(&pts, xyz, N_EXACT) == QRT_OK, "add");
    CHECK(pts.voxel_m == 0.0 && pts.count + pts.ignored_far == N_EXACT,
          "exact table of %ld", pts.count);
    sorted_rows(&pts, rows_before);
    before = median_block_diagonal(&pts);
    qrt_points_order(&pts, scratch_a, scratch_b);
    sorted_rows(&pts, rows_after);
    CHECK(memcmp(rows_before, rows_after,
                 (size_t)pts.count * sizeof rows_before[0]) == 0,
          "ordering changed the table's points");
    for (i = 1; i < pts.count; i++)
        out_of_order += morton(&pts, i - 1) > morton(&pts, i);
    CHECK(out_of_order == 0, "%ld entries out of Morton order", out_of_order);
    after = median_block_diagonal(&pts);
    printf("median block diagonal: %.3f m as given, %.3f m ordered\n", before,
           after);
    CHECK(after < before / 4, "blocks not compact: %.3f m, %.3f m before",
          after, before);
}

/* Entry i of p, whole: its point and its box. */
static int same_entry(const struct qrt_points *p, long i,
                      const struct qrt_points *o, long j)
{
    int k,
        same = p->x[i] == o->x[j] && p->y[i] == o->y[j] && p->z[i] == o->z[j];
    for (k = 0; k < 3; k++)
        same = same && p->box_lo[k][i] == o->box_lo[k][j] &&
               p->box_hi[k][i] == o->box_hi[k][j];
    return same;
}

/* Voxel mode: each hash slot names, after ordering, the very entry (point
 * and box) it named before, so every voxel is found again, and the
 * entries are the same ones. */
static void check_voxels(void)
{
    struct qrt_params prm;
    long n = 2 * QRT_MAX_POINTS, s, named = 0, wrong = 0, emptied = 0;
    qrt_params_default(&prm);
    qrt_points_reset(&pts, qrt_arm_reach_m(&prm.arm) + prm.margin_m);
    wall_points(n);
    CHECK(qrt_points_add(&pts, xyz, n) == QRT_OK, "add");
    CHECK(pts.voxel_m > 0.0 && pts.dropped == 0, "voxel table (%g m)",
          pts.voxel_m);
    copy = pts;
    sorted_rows(&pts, rows_before);
    qrt_points_order(&pts, scratch_a, scratch_b);
    sorted_rows(&pts, rows_after);
    CHECK(memcmp(rows_before, rows_after,
                 (size_t)pts.count * sizeof rows_before[0]) == 0,
          "ordering changed the voxel table's points");
    for (s = 0; s < QRT_POINT_HASH_SLOTS; s++) {
        emptied += (pts.hash[s] == 0u) != (copy.hash[s] == 0u);
        if (pts.hash[s] != 0u && copy.hash[s] != 0u) {
            named++;
            wrong += !same_entry(&pts, (long)pts.hash[s] - 1, &copy,
                                 (long)copy.hash[s] - 1);
        }
    }
    CHECK(emptied == 0, "%ld hash slots emptied or filled", emptied);
    CHECK(named == pts.count && wrong == 0,
          "%ld slots name %ld entries, %ld of them another entry than before",
          named, pts.count, wrong);
}

/* With and without the boxes, the same clearance (capped), at random
 * configurations of the arm among the ordered walls. */
static void check_boxes(void)
{
    struct qrt_params prm;
    long i, colliding = 0;
    double radius[3];
    int k;
    qrt_params_default(&prm);
    qrt_points_reset(&pts, qrt_arm_reach_m(&prm.arm) + prm.margin_m);
    wall_points(N_EXACT);
    qrt_points_add(&pts, xyz, N_EXACT);
    qrt_points_order(&pts, scratch_a, scratch_b);
    qrt_points_block_boxes(&pts, boxes);
    for (k = 0; k < 3; k++)
        radius[k] = prm.arm.link_radius_m[k] + prm.margin_m;
    for (i = 0; i < test_count(400); i++) {
        double q[3], p[4][3],
            cap = i % 3 == 0   ? 1e30
                  : i % 3 == 1 ? 0.05
                               : 0.01,
            plain, boxed;
        q[0] = test_uniform(-180, 180);
        q[1] = test_uniform(-40, 180);
        q[2] = test_uniform(-180, 140);
        qrt_arm_fk(&prm.arm, q, p);
        plain = qrt_chain_clearance_capped((const double(*)[3])p, radius, 3,
                                           &pts, NULL, cap);
        boxed = qrt_chain_clearance_capped((const double(*)[3])p, radius, 3,
                                           &pts, (const float(*)[6])boxes, cap);
        colliding += plain <= 0.0;
        CHECK(plain <= 0.0 ? boxed <= 0.0 : boxed == plain,
              "q (%g %g %g) cap %g: %.17g with boxes, %.17g without", q[0],
              q[1], q[2], cap, boxed, plain);
    }
    CHECK(colliding > test_count(400) / 10 && colliding < test_count(400),
          "%ld of the configurations collide: the walls do not test both",
          colliding);
}

/* The certificate orders the table of a planner whose lazily built mask
 * keeps clusters that name their points by place: they are renumbered, so
 * the rows built after it, by a path check and by a second plan, are those
 * of a planner that never ordered its table. */
static void check_kept_clusters(void)
{
    struct qrt_params prm;
    struct qrt_target start, goal;
    struct qrt_plan a, b;
    long trial, checks = 0, blocked = 0;
    qrt_params_default(&prm);
    wall_points(N_EXACT);
    CHECK(qrt_planner_init(&certified, &prm) == QRT_OK &&
              qrt_planner_init(&fresh, &prm) == QRT_OK,
          "init");
    qrt_planner_add_points(&certified, xyz, N_EXACT);
    qrt_planner_add_points(&fresh, xyz, N_EXACT);
    start.kind = goal.kind = QRT_TARGET_JOINTS;
    start.ik.facing = goal.ik.facing = QRT_FACING_ANY;
    start.ik.elbow = goal.ik.elbow = QRT_ELBOW_ANY;
    /* reaching out between the walls: the straight motion would put the
     * tool through the front wall */
    start.value[0] = -40.0;
    start.value[1] = 90.0;
    start.value[2] = -90.0;
    goal.value[0] = 40.0;
    goal.value[1] = 90.0;
    goal.value[2] = -90.0;
    CHECK(qrt_planner_plan_now(&certified, &start, &goal, &a) == QRT_OK,
          "plan");
    CHECK(qrt_planner_mask_state(&certified) == QRT_MASK_PARTIAL,
          "the mask is built as read, its clusters kept (state %d)",
          (int)qrt_planner_mask_state(&certified));
    CHECK(a.status == QRT_STATUS_OK, "a path (%s)", a.detail);
    CHECK(qrt_planner_certify_clearance(&certified, &a) == QRT_OK &&
              a.clearance_m >= prm.margin_m,
          "certified %g", a.clearance_m);
    CHECK(certified.points_ordered, "the certificate ordered the table");
    for (trial = 0; trial < test_count(60); trial++) {
        double wp[3][3];
        int j, k, first_a, first_b;
        for (j = 0; j < 3; j++) {
            wp[j][0] = test_uniform(-180, 180);
            wp[j][1] = test_uniform(-40, 180);
            wp[j][2] = test_uniform(-180, 140);
        }
        k = qrt_planner_check_path_now(&certified, (const double(*)[3])wp, 3,
                                       &first_a);
        CHECK(k == QRT_OK &&
                  qrt_planner_check_path_now(&fresh, (const double(*)[3])wp, 3,
                                             &first_b) == QRT_OK,
              "check");
        CHECK(first_a == first_b, "trial %ld: first blocked %d, unordered %d",
              trial, first_a, first_b);
        checks++;
        blocked += first_b >= 0;
    }
    CHECK(blocked > 0 && blocked < checks, "%ld of %ld paths blocked", blocked,
          checks);
    start.value[1] = 120.0; /* from another start */
    start.value[2] = -100.0;
    CHECK(qrt_planner_plan_now(&certified, &start, &goal, &a) == QRT_OK &&
              qrt_planner_plan_now(&fresh, &start, &goal, &b) == QRT_OK,
          "second plans");
    CHECK(a.status == QRT_STATUS_OK && a.status == b.status &&
              a.n_waypoints == b.n_waypoints &&
              memcmp(a.waypoints_deg, b.waypoints_deg,
                     (size_t)a.n_waypoints * sizeof a.waypoints_deg[0]) == 0 &&
              a.nodes_expanded == b.nodes_expanded,
          "the second plan differs: %s %d waypoints %ld expanded, "
          "unordered %s %d %ld",
          a.detail, a.n_waypoints, a.nodes_expanded, b.detail, b.n_waypoints,
          b.nodes_expanded);
}

int main(void)
{
    test_seed(2718);
    check_exact();
    check_voxels();
    check_boxes();
    check_kept_clusters();
    return test_done("test_order");
}
