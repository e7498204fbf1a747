/* The paper's Table 5 experiment, timed: n spheres x k points (its Eq. 13
 * family, src/cli/gen.c), end to end (init + points + plan asking only the
 * mask nodes it reads, qrt_planner_plan_now), median of repeated runs,
 * beside the paper's seconds; each run alternates with the same plan from
 * the whole mask (qrt_planner_build_mask + qrt_planner_plan), which gives
 * the conversion / search split. Also 10 spheres with 10^4, 10^5 and 10^6
 * points each.
 *
 * The last lines build the 10 x 1444 mask with two threads
 * (qrt_planner_build_mask_part), interleaved with single-threaded runs,
 * and ask whether a path is still free (--check-path alone).
 *
 *   bench_table5 [--repeats R] [--quick] [--csv FILE] [--single N K]
 *                [--threads 1|2] [--check-path]
 */
#define _POSIX_C_SOURCE 200809L
#include <pthread.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "args.h"
#include "gen.h"
#include "qrtplan/qrtplan.h"

static const int table_points[9] = {16, 25, 36, 49, 64, 100, 169, 361, 1444};
/* Table 5 of the paper, seconds (its "17/484" read as 17.484) */
static const double paper_s[10][9] = {
    {0.563, 0.656, 0.750, 0.875, 1.094, 2.500, 3.000, 4.484, 13.484},
    {0.906, 1.016, 1.156, 1.328, 1.938, 4.797, 5.766, 8.781, 23.219},
    {1.234, 1.453, 1.703, 2.063, 2.109, 6.812, 8.859, 12.766, 36.109},
    {1.484, 1.859, 2.047, 2.297, 2.859, 9.125, 11.672, 17.484, 49.453},
    {1.906, 2.406, 2.578, 2.766, 3.469, 11.250, 13.875, 20.656, 61.234},
    {2.188, 2.594, 3.250, 3.969, 4.094, 13.484, 17.297, 27.344, 76.609},
    {2.344, 2.938, 3.406, 4.078, 5.891, 15.406, 19.094, 28.969, 82.953},
    {2.813, 3.172, 4.016, 4.313, 5.031, 17.422, 22.172, 33.875, 97.359},
    {3.094, 3.641, 4.031, 4.828, 5.531, 19.469, 24.469, 37.234, 109.953},
    {3.219, 4.266, 4.781, 6.063, 6.531, 21.547, 27.531, 41.359, 126.500}};

static struct qrt_planner pl;
static int mask_threads = 1;

static void *build_part_one(void *arg)
{
    (void)arg;
    qrt_planner_build_mask_part(&pl, 1, 2);
    return NULL;
}

/* the mask on mask_threads threads: part 1 on a second thread, part 0 here */
static void build_mask(void)
{
    pthread_t t;
    int threaded;
    if (mask_threads < 2) {
        qrt_planner_build_mask(&pl);
        return;
    }
    qrt_planner_build_mask_begin(&pl);
    threaded = pthread_create(&t, NULL, build_part_one, NULL) == 0;
    qrt_planner_build_mask_part(&pl, 0, 2);
    if (threaded)
        pthread_join(t, NULL);
    else
        qrt_planner_build_mask_part(&pl, 1, 2);
    qrt_planner_build_mask_end(&pl);
}

static double now_s(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

static int cmp_double(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return (x > y) - (x < y);
}

struct cell {
    double median_ms, min_ms, whole_ms, convert_ms, search_ms;
    long points, blocked, expanded;
    const char *status;
};

/* Spheres on a circle with the start and goal (sigma = eta = 0) in the gaps
 * between them, so that every plan has to find its way round: one sphere
 * sits behind the arm as in Table 4. */
static void scene_for(int n, struct sphere_layout *L, double start[3],
                      double goal[3])
{
    sphere_layout_default(L);
    L->spheres = n;
    start[1] = start[2] = goal[1] = goal[2] = 0.0;
    if (n == 1) {
        start[0] = -100.0;
        goal[0] = 100.0;
        return;
    }
    L->phase_deg = 90.0 - 180.0 / n;
    goal[0] = 90.0;
    start[0] = 90.0 - 360.0 * (n / 2) / n;
}

/* One end-to-end plan as qrtplan makes it (init, points, then
 * qrt_planner_plan_now: only the mask nodes the plan reads are asked).
 * Never inlined: tools/bench.sh counts its instructions with callgrind's
 * --toggle-collect, which must name one function that is entered once per
 * plan (the qrt_planner_* calls nest, and nested matches would toggle the
 * count off again). */
__attribute__((noinline)) void plan_end_to_end(const struct qrt_params *prm,
                                               const double *xyz, long count,
                                               const struct qrt_target *s,
                                               const struct qrt_target *g,
                                               struct qrt_plan *plan)
{
    qrt_planner_init(&pl, prm);
    qrt_planner_add_points(&pl, xyz, count);
    qrt_planner_plan_now(&pl, s, g, plan);
}

/* The same plan from the whole mask (qrt_planner_build_mask, on
 * mask_threads threads, then qrt_planner_plan), stamped after the mask. */
__attribute__((noinline)) void
plan_whole_mask(const struct qrt_params *prm, const double *xyz, long count,
                const struct qrt_target *s, const struct qrt_target *g,
                struct qrt_plan *plan, double *t_mask)
{
    qrt_planner_init(&pl, prm);
    qrt_planner_add_points(&pl, xyz, count);
    build_mask();
    *t_mask = now_s();
    qrt_planner_plan(&pl, s, g, plan);
}

/* Both ways, alternating, so that machine noise falls on both alike; the
 * whole-mask runs give the conversion / search split and the mask's
 * statistics. */
static void run_cell(int n, int k, int repeats, struct cell *c)
{
    struct sphere_layout L;
    struct qrt_params prm;
    struct qrt_target s = {
        QRT_TARGET_JOINTS, {0, 0, 0}, {QRT_FACING_ANY, QRT_ELBOW_ANY}};
    struct qrt_target g = {
        QRT_TARGET_JOINTS, {0, 0, 0}, {QRT_FACING_ANY, QRT_ELBOW_ANY}};
    static struct qrt_plan plan, whole_plan;
    double *xyz, *times = malloc((size_t)repeats * sizeof *times);
    double *whole = malloc((size_t)repeats * sizeof *whole);
    double conv = 0.0, search = 0.0;
    long count;
    int r;
    scene_for(n, &L, s.value, g.value);
    L.points = k;
    count = sphere_layout_count(&L);
    xyz = malloc((size_t)count * 3 * sizeof *xyz);
    if (!xyz || !times || !whole) {
        fprintf(stderr, "out of memory\n");
        exit(1);
    }
    sphere_layout_points(&L, xyz);
    qrt_params_default(&prm);
    for (r = 0; r < repeats; r++) {
        double t0 = now_s(), t1, t2, t3;
        plan_end_to_end(&prm, xyz, count, &s, &g, &plan);
        t1 = now_s();
        plan_whole_mask(&prm, xyz, count, &s, &g, &whole_plan, &t2);
        t3 = now_s();
        times[r] = (t1 - t0) * 1e3;
        whole[r] = (t3 - t1) * 1e3;
        conv += (t2 - t1) * 1e3;
        search += (t3 - t2) * 1e3;
    }
    qsort(times, (size_t)repeats, sizeof *times, cmp_double);
    qsort(whole, (size_t)repeats, sizeof *whole, cmp_double);
    c->median_ms = times[repeats / 2];
    c->min_ms = times[0];
    c->whole_ms = whole[repeats / 2];
    c->convert_ms = conv / repeats;
    c->search_ms = search / repeats;
    c->points = count;
    c->blocked = whole_plan.cells_blocked;
    c->expanded = whole_plan.nodes_expanded;
    c->status = qrt_plan_status_name(plan.status);
    if (plan.status != whole_plan.status ||
        plan.n_waypoints != whole_plan.n_waypoints ||
        plan.cost_deg != whole_plan.cost_deg) {
        fprintf(stderr, "%d x %d: the two ways planned differently\n", n, k);
        exit(1);
    }
    free(xyz);
    free(times);
    free(whole);
}

/* A replan's first question, "is the path being executed still free?",
 * asked of a new 10 x 1444 cloud two ways, alternating: by
 * qrt_planner_check_path_now (only the rows the path passes through) and
 * by building the whole mask and then qrt_planner_check_path. */
static void check_now_vs_mask(int repeats)
{
    struct sphere_layout L;
    struct qrt_params prm;
    struct qrt_target s = {
        QRT_TARGET_JOINTS, {0, 0, 0}, {QRT_FACING_ANY, QRT_ELBOW_ANY}};
    struct qrt_target g = {
        QRT_TARGET_JOINTS, {0, 0, 0}, {QRT_FACING_ANY, QRT_ELBOW_ANY}};
    static struct qrt_plan plan;
    double now_ms[15], full_ms[15], *xyz;
    long count;
    int r, rep = repeats < 15 ? repeats : 15, blocked_now = 0, blocked_full = 0;
    scene_for(10, &L, s.value, g.value);
    L.points = 1444;
    count = sphere_layout_count(&L);
    xyz = malloc((size_t)count * 3 * sizeof *xyz);
    if (!xyz)
        return;
    sphere_layout_points(&L, xyz);
    qrt_params_default(&prm);
    qrt_planner_init(&pl, &prm);
    qrt_planner_add_points(&pl, xyz, count);
    qrt_planner_build_mask(&pl);
    qrt_planner_plan(&pl, &s, &g, &plan);
    for (r = 0; r < rep && plan.status == QRT_STATUS_OK; r++) {
        double t0, t1, t2;
        const double(*wp)[3] = (const double(*)[3])plan.waypoints_deg;
        qrt_planner_clear_points(&pl); /* a new scan of the same scene */
        qrt_planner_add_points(&pl, xyz, count);
        t0 = now_s();
        qrt_planner_check_path_now(&pl, wp, plan.n_waypoints, &blocked_now);
        t1 = now_s();
        build_mask();
        qrt_planner_check_path(&pl, wp, plan.n_waypoints, &blocked_full);
        t2 = now_s();
        now_ms[r] = (t1 - t0) * 1e3;
        full_ms[r] = (t2 - t1) * 1e3;
    }
    free(xyz);
    if (plan.status != QRT_STATUS_OK || rep < 1)
        return;
    qsort(now_ms, (size_t)rep, sizeof *now_ms, cmp_double);
    qsort(full_ms, (size_t)rep, sizeof *full_ms, cmp_double);
    printf("10 x 1444, is the %d-waypoint path still free? "
           "check_path_now %.2f ms, whole mask + check_path %.2f ms (%.1fx); "
           "answers %d and %d; %d runs each\n",
           plan.n_waypoints, now_ms[rep / 2], full_ms[rep / 2],
           full_ms[rep / 2] / now_ms[rep / 2], blocked_now, blocked_full, rep);
}

int main(int argc, char **argv)
{
    static const long big[3] = {10000, 100000, 1000000};
    int repeats = 15, i, n, k, single_n = 0, single_k = 0, check_only = 0;
    const char *csv_path = NULL;
    FILE *csv = NULL;
    struct cell c;
    for (i = 1; i < argc; i++) {
        int bad = 0;
        if (strcmp(argv[i], "--repeats") == 0 && i + 1 < argc)
            bad = args_int(argv[++i], 10, 0, 1000000, &repeats);
        else if (strcmp(argv[i], "--quick") == 0)
            repeats = 3;
        else if (strcmp(argv[i], "--csv") == 0 && i + 1 < argc)
            csv_path = argv[++i];
        else if (strcmp(argv[i], "--single") == 0 && i + 2 < argc) {
            bad = args_int(argv[i + 1], 10, 1, 1000, &single_n) ||
                  args_int(argv[i + 2], 10, 4, 100000000, &single_k);
            i += 2;
        } else if (strcmp(argv[i], "--check-path") == 0) {
            check_only = 1;
        } else if (strcmp(argv[i], "--threads") == 0 && i + 1 < argc) {
            bad = args_int(argv[++i], 10, 1, 2, &mask_threads);
        } else {
            bad = 1;
        }
        if (bad) {
            fprintf(stderr, "usage: bench_table5 [--repeats R] [--quick] "
                            "[--csv FILE] [--single SPHERES POINTS] "
                            "[--threads 1|2] [--check-path]\n");
            return 2;
        }
    }
    if (repeats < 1)
        repeats = 1;
    if (check_only) {
        check_now_vs_mask(repeats);
        return 0;
    }
    if (single_n > 0) {
        run_cell(single_n, single_k, repeats, &c);
        printf(
            "%d x %d: %s, median %.3f ms (nodes asked as read); whole mask "
            "%.3f ms (convert %.3f ms, search %.3f ms); %ld nodes expanded\n",
            single_n, single_k, c.status, c.median_ms, c.whole_ms, c.convert_ms,
            c.search_ms, c.expanded);
        return 0;
    }
    if (csv_path && !(csv = fopen(csv_path, "w"))) {
        perror(csv_path);
        return 1;
    }
    if (csv)
        fprintf(csv, "spheres,points_per_sphere,points,status,median_ms,"
                     "min_ms,whole_mask_median_ms,convert_ms,search_ms,"
                     "cells_blocked,nodes_expanded,paper_s,speedup\n");
    printf("Table 5: end-to-end plan time (qrt_planner_plan_now), median of "
           "%d runs, ms (paper's seconds in brackets, speed-up below)\n",
           repeats);
    printf("%7s", "spheres");
    for (k = 0; k < 9; k++)
        printf(" %13d", table_points[k]);
    printf("\n");
    for (n = 1; n <= 10; n++) {
        double speed[9];
        printf("%7d", n);
        for (k = 0; k < 9; k++) {
            run_cell(n, table_points[k], repeats, &c);
            speed[k] = paper_s[n - 1][k] * 1e3 / c.median_ms;
            printf(" %6.2f[%5.1f]%s", c.median_ms, paper_s[n - 1][k],
                   strcmp(c.status, "ok") ? "!" : "");
            fflush(stdout);
            if (csv)
                fprintf(csv,
                        "%d,%d,%ld,%s,%.4f,%.4f,%.4f,%.4f,%.4f,%ld,%ld,%.3f,"
                        "%.1f\n",
                        n, table_points[k], c.points, c.status, c.median_ms,
                        c.min_ms, c.whole_ms, c.convert_ms, c.search_ms,
                        c.blocked, c.expanded, paper_s[n - 1][k], speed[k]);
        }
        printf("\n%7s", "x");
        for (k = 0; k < 9; k++)
            printf(" %13.0f", speed[k]);
        printf("\n");
    }
    printf("('!' marks a plan whose status was not ok)\n\n");
    printf("10 spheres, larger clouds (median of %d runs)\n",
           repeats > 3 ? 3 : repeats);
    for (i = 0; i < 3; i++) {
        run_cell(10, (int)big[i], repeats > 3 ? 3 : repeats, &c);
        printf("  %8ld points/sphere: %9.2f ms; whole mask %.2f ms (convert "
               "%.2f, search %.2f), %s\n",
               c.points / 10, c.median_ms, c.whole_ms, c.convert_ms,
               c.search_ms, c.status);
        if (csv)
            fprintf(csv, "10,%ld,%ld,%s,%.4f,%.4f,%.4f,%.4f,%.4f,%ld,%ld,,\n",
                    big[i], c.points, c.status, c.median_ms, c.min_ms,
                    c.whole_ms, c.convert_ms, c.search_ms, c.blocked,
                    c.expanded);
    }
    {
        /* one and two threads for the whole mask, alternating, so that
         * machine noise falls on both alike, beside the nodes asked as read */
        double one[15], two[15], lazy[15];
        int saved = mask_threads, rep = repeats < 15 ? repeats : 15;
        for (i = 0; i < rep; i++) {
            mask_threads = 1;
            run_cell(10, 1444, 1, &c);
            one[i] = c.whole_ms;
            lazy[i] = c.median_ms;
            mask_threads = 2;
            run_cell(10, 1444, 1, &c);
            two[i] = c.whole_ms;
        }
        mask_threads = saved;
        qsort(one, (size_t)rep, sizeof *one, cmp_double);
        qsort(two, (size_t)rep, sizeof *two, cmp_double);
        qsort(lazy, (size_t)rep, sizeof *lazy, cmp_double);
        printf("\n10 x 1444, whole mask on two threads "
               "(qrt_planner_build_mask_part): median %.2f ms vs %.2f ms on "
               "one (%.2fx); nodes asked as read (qrt_planner_plan_now, one "
               "thread) %.2f ms (%.2fx the whole mask on one); %d runs each\n",
               two[rep / 2], one[rep / 2], one[rep / 2] / two[rep / 2],
               lazy[rep / 2], one[rep / 2] / lazy[rep / 2], rep);
    }
    check_now_vs_mask(repeats);
    if (csv)
        fclose(csv);
    return 0;
}
