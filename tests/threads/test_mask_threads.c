/* The mask built by two threads at once (qrt_planner_build_mask_part on
 * each) equals the single-threaded mask bit for bit, on the paper's
 * 10-sphere scene and on random clutter. The ASan build runs it too. */
#include <pthread.h>
#include <string.h>

#include "../unit/check.h"
#include "qrtplan/qrtplan.h"

static struct qrt_planner pl;
static struct qrt_mask whole;
static double cloud[3 * 16000];

struct job {
    int part;
    int rc;
};

static void *build_part(void *arg)
{
    struct job *j = arg;
    j->rc = qrt_planner_build_mask_part(&pl, j->part, 2);
    return NULL;
}

/* the paper's Eq. 13 family: n spheres of radius 0.1 m on a 0.6 m circle */
static long spheres(int n, int k)
{
    long count = 0;
    int s, i, j;
    for (s = 0; s < n; s++) {
        double b = 3.14159265358979 + 2 * 3.14159265358979 * s / n;
        double c[3] = {0.6 * cos(b), 0.6 * sin(b), 0.1};
        for (i = 0; i < k; i++)
            for (j = 0; j < k; j++) {
                double t = 2 * 3.14159265358979 * i / k;
                double u = -1.5707963 + 3.14159265358979 * j / (k - 1);
                cloud[3 * count] = c[0] + 0.1 * cos(t) * cos(u);
                cloud[3 * count + 1] = c[1] + 0.1 * sin(t) * cos(u);
                cloud[3 * count + 2] = c[2] + 0.1 * sin(u);
                count++;
            }
    }
    return count;
}

int main(void)
{
    int trial;
    test_seed(77);
    for (trial = 0; trial < test_count(12); trial++) {
        struct qrt_params prm;
        struct job jobs[2] = {{0, -99}, {1, -99}};
        pthread_t t[2];
        long n, i;
        if (trial == 0) {
            n = spheres(10, 38);
        } else {
            n = 200 * (1 + trial);
            for (i = 0; i < 3 * n; i++)
                cloud[i] = test_uniform(-0.9, 0.9);
        }
        qrt_params_default(&prm);
        qrt_planner_init(&pl, &prm);
        qrt_planner_add_points(&pl, cloud, n);
        qrt_planner_build_mask(&pl);
        whole = pl.mask;
        qrt_planner_build_mask_begin(&pl);
        CHECK(pthread_create(&t[0], NULL, build_part, &jobs[0]) == 0, "thread");
        CHECK(pthread_create(&t[1], NULL, build_part, &jobs[1]) == 0, "thread");
        pthread_join(t[0], NULL);
        pthread_join(t[1], NULL);
        qrt_planner_build_mask_end(&pl);
        CHECK(jobs[0].rc == QRT_OK && jobs[1].rc == QRT_OK, "part failed");
        CHECK(memcmp(pl.mask.rows, whole.rows, sizeof whole.rows) == 0,
              "trial %d (%ld points): threaded mask differs", trial, n);
        CHECK(pl.cells_blocked > 0, "trial %d blocks nothing", trial);
    }
    return test_done("test_mask_threads");
}
