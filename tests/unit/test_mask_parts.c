/* Building the mask in parts (qrt_planner_build_mask_begin/_part/_end) gives
 * the mask of qrt_planner_build_mask bit for bit, whatever order the parts
 * run in, and each part writes only its own alpha slices. The threaded case
 * is tests/threads/test_mask_threads.c (host only). */
#include <string.h>

#include "check.h"
#include "qrtplan/qrtplan.h"

static struct qrt_planner pl;
static struct qrt_mask whole;
static double cloud[3 * 4000];

static long make_cloud(void)
{
    long n = 0;
    int blobs = 1 + (int)test_uniform(0, 15), i, j;
    for (i = 0; i < blobs; i++) {
        double c[3] = {test_uniform(-0.9, 0.9), test_uniform(-0.9, 0.9),
                       test_uniform(-0.4, 0.9)};
        double size = test_uniform(0.01, 0.2);
        int count = 1 + (int)test_uniform(0, 250);
        for (j = 0; j < count; j++) {
            cloud[3 * n] = c[0] + test_uniform(-size, size);
            cloud[3 * n + 1] = c[1] + test_uniform(-size, size);
            cloud[3 * n + 2] = c[2] + test_uniform(-size, size);
            n++;
        }
    }
    return n;
}

static int same_mask(const struct qrt_mask *a, const struct qrt_mask *b)
{
    return memcmp(a->rows, b->rows, sizeof a->rows) == 0;
}

int main(void)
{
    long trial, differing = 0, nonempty = 0;
    test_seed(4242);
    for (trial = 0; trial < test_count(40); trial++) {
        struct qrt_params prm;
        long n = make_cloud(), blocked;
        qrt_params_default(&prm);
        prm.grid_deg = trial % 3 == 0 ? 10.0 : 5.0;
        prm.cspace_margin_deg = trial % 4 == 1 ? 2.0 : 0.0;
        CHECK(qrt_planner_init(&pl, &prm) == QRT_OK, "init");
        CHECK(qrt_planner_add_points(&pl, cloud, n) == QRT_OK, "points");
        qrt_planner_build_mask(&pl);
        whole = pl.mask;
        blocked = pl.cells_blocked;
        nonempty += blocked > 0;

        /* two parts, the second first: same mask, same count */
        CHECK(qrt_planner_build_mask_begin(&pl) == QRT_OK, "begin");
        CHECK(qrt_planner_build_mask_part(&pl, 1, 2) == QRT_OK, "part 1");
        CHECK(qrt_planner_build_mask_part(&pl, 0, 2) == QRT_OK, "part 0");
        CHECK(qrt_planner_build_mask_end(&pl) == QRT_OK, "end");
        CHECK(same_mask(&pl.mask, &whole), "trial %ld: parts differ", trial);
        CHECK(pl.cells_blocked == blocked, "trial %ld: %ld vs %ld blocked",
              trial, pl.cells_blocked, blocked);

        /* part 1 alone: exactly the odd alpha slices of the whole mask */
        qrt_planner_build_mask_begin(&pl);
        qrt_planner_build_mask_part(&pl, 1, 2);
        {
            int ia, ok = 1;
            for (ia = 0; ia < QRT_MAX_NA; ia++) {
                int want_empty = ia % 2 == 0;
                size_t bytes = sizeof pl.mask.rows[ia];
                static const uint64_t zero[QRT_MAX_NS][QRT_ROW_WORDS];
                if (want_empty)
                    ok &= memcmp(pl.mask.rows[ia], zero, bytes) == 0;
                else
                    ok &= memcmp(pl.mask.rows[ia], whole.rows[ia], bytes) == 0;
            }
            CHECK(ok, "trial %ld: part 1 wrote outside its alpha slices",
                  trial);
            differing += !same_mask(&pl.mask, &whole);
        }
        /* a plan on a half-built mask is refused */
        {
            struct qrt_target s = {
                QRT_TARGET_JOINTS, {0, 0, 0}, {QRT_FACING_ANY, QRT_ELBOW_ANY}};
            struct qrt_plan plan;
            CHECK(qrt_planner_plan(&pl, &s, &s, &plan) == QRT_E_INVALID,
                  "a plan before _end must be refused");
        }
        qrt_planner_build_mask_end(&pl);
    }
    CHECK(nonempty >= test_count(40) / 2, "too few scenes block anything");
    CHECK(differing >= nonempty / 2, "half a mask equals the whole too often");
    CHECK(qrt_planner_build_mask_part(&pl, 2, 2) == QRT_E_INVALID, "part 2/2");
    CHECK(qrt_planner_build_mask_part(&pl, -1, 2) == QRT_E_INVALID, "part -1");
    CHECK(qrt_planner_build_mask_part(&pl, 0, 3) == QRT_E_INVALID, "3 parts");
    CHECK(qrt_planner_build_mask_part(&pl, 0, 0) == QRT_E_INVALID, "0 parts");
    return test_done("test_mask_parts");
}
