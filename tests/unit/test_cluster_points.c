/* qrt_cluster_points, the bucketing of points into cubes, against a plain
 * count: every point comes in exactly one group, a group's points share a
 * cube (by floor of coordinate / cell), no group is larger than asked, and
 * a cube's points come in as few groups as the size limit allows. Cells of
 * 4 cm (every cube key fits the packed 10 bits per axis) and of 0.5 mm
 * (keys beyond +-512 for points farther than 0.26 m: compared whole). */
#include <math.h>
#include <stdint.h>

#include "../../src/core/cluster.h"
#include "check.h"

#define N_POINTS 3000
#define MAX_MEMBERS 7

static float pts[N_POINTS][3];
/* the same points by axis, as the clusterer reads them */
static float axis[3][N_POINTS];
static int32_t scratch[4 * N_POINTS + 8192];
static int seen[N_POINTS];

struct tally {
    double cell;
    long groups, bad_cube, too_big;
};

static void key_of(const float p[3], double cell, long key[3])
{
    int k;
    for (k = 0; k < 3; k++)
        key[k] = (long)floor((double)p[k] * (1.0 / cell));
}

static void visit(void *ctx, const int32_t *members, int m)
{
    struct tally *t = (struct tally *)ctx;
    long first[3];
    int j;
    t->groups++;
    if (m > MAX_MEMBERS || m < 1)
        t->too_big++;
    key_of(pts[members[0]], t->cell, first);
    for (j = 0; j < m; j++) {
        long key[3];
        seen[members[j]]++;
        key_of(pts[members[j]], t->cell, key);
        if (key[0] != first[0] || key[1] != first[1] || key[2] != first[2])
            t->bad_cube++;
    }
}

/* Groups a perfect bucketing makes: each cube's count over MAX_MEMBERS,
 * rounded up (n^2 over distinct cubes; n is small). */
static long groups_expected(long n, double cell)
{
    long i, j, total = 0;
    for (i = 0; i < n; i++) {
        long ki[3], count = 0;
        int first = 1;
        key_of(pts[i], cell, ki);
        for (j = 0; j < n && first; j++) {
            long kj[3];
            key_of(pts[j], cell, kj);
            if (ki[0] == kj[0] && ki[1] == kj[1] && ki[2] == kj[2]) {
                if (j < i)
                    first = 0; /* counted at its first point */
                count++;
            }
        }
        if (first) {
            for (; j < n; j++) {
                long kj[3];
                key_of(pts[j], cell, kj);
                count += ki[0] == kj[0] && ki[1] == kj[1] && ki[2] == kj[2];
            }
            total += (count + MAX_MEMBERS - 1) / MAX_MEMBERS;
        }
    }
    return total;
}

int main(void)
{
    static const double cells[2] = {0.04, 0.0005};
    int trial;
    test_seed(0x5eedULL);
    for (trial = 0; trial < 2 * (int)test_count(3); trial++) {
        struct tally t = {0.0, 0, 0, 0};
        struct qrt_point_axes ax;
        long n = 200 + (long)test_uniform(0.0, N_POINTS - 200), i, once = 0;
        t.cell = cells[trial % 2];
        for (i = 0; i < n; i++) { /* dense blobs, so that cubes share */
            int k;
            for (k = 0; k < 3; k++)
                pts[i][k] = (float)(test_uniform(-1.0, 1.0) *
                                    (i % 3 == 0 ? 1.0 : 0.02 + 0.001 * k));
            seen[i] = 0;
        }
        CHECK(qrt_cluster_scratch_len(n) <=
                  (long)(sizeof scratch / sizeof scratch[0]),
              "scratch");
        for (i = 0; i < n; i++) {
            int k;
            for (k = 0; k < 3; k++)
                axis[k][i] = pts[i][k];
        }
        ax.x = axis[0];
        ax.y = axis[1];
        ax.z = axis[2];
        qrt_cluster_points(&ax, n, t.cell, MAX_MEMBERS, scratch, visit, &t);
        for (i = 0; i < n; i++)
            once += seen[i] == 1;
        CHECK(once == n, "cell %g: %ld of %ld points in exactly one group",
              t.cell, once, n);
        CHECK(t.bad_cube == 0 && t.too_big == 0,
              "cell %g: %ld points outside their group's cube, %ld groups "
              "too large",
              t.cell, t.bad_cube, t.too_big);
        CHECK(t.groups == groups_expected(n, t.cell),
              "cell %g: %ld groups, expected %ld", t.cell, t.groups,
              groups_expected(n, t.cell));
    }
    return test_done("test_cluster_points");
}
