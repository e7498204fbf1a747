/* A program outside qrtplan that links the installed core: it plans the
 * paper's Table 4 scene (one sphere of 1,444 points, radius 0.1 m, centred
 * 0.6 m behind the base; alpha from -100 to 100 degrees across +-180) and
 * prints the plan, one waypoint a line.
 *
 * Built with CMake (CMakeLists.txt beside it), or in one line:
 *   cc -std=c99 table4.c $(pkg-config --cflags --libs qrtplan) -o table4
 * with PKG_CONFIG_PATH=PREFIX/lib/pkgconfig. */
#include <math.h>
#include <stdio.h>

#include "qrtplan/qrtplan.h"

#define K 38 /* 38 x 38 = 1,444 points */

/* the planner's state is large and fixed: static, as on a board */
static struct qrt_planner planner;
static double points[K * K][3];

/* The paper's Eq. 13 sphere, sampled as `qrtplan gen` samples it: k x k
 * pairs of its two angles, the first over a whole turn, the second from
 * pole to pole. */
static void sphere(double cx, double cy, double cz, double r)
{
    const double pi = 3.14159265358979323846;
    int i, j, n = 0;
    for (i = 0; i < K; i++)
        for (j = 0; j < K; j++) {
            double t1 = -pi + 2.0 * pi * i / K;
            double t2 = -0.5 * pi + pi * j / (K - 1);
            points[n][0] = cx + r * cos(t1) * cos(t2);
            points[n][1] = cy + r * sin(t1) * cos(t2);
            points[n][2] = cz + r * sin(t2);
            n++;
        }
}

int main(void)
{
    struct qrt_params params;
    struct qrt_target start = {
        QRT_TARGET_JOINTS, {-100, 0, 0}, {QRT_FACING_ANY, QRT_ELBOW_ANY}};
    struct qrt_target goal = {
        QRT_TARGET_JOINTS, {100, 0, 0}, {QRT_FACING_ANY, QRT_ELBOW_ANY}};
    struct qrt_plan plan;
    char why[QRT_ABI_MESSAGE_LEN];
    int rc, i;

    qrt_params_default(&params); /* the paper's arm, 5 degrees, 0.01 m */
    rc = qrt_planner_init(&planner, &params);
    if (rc == QRT_E_ABI) { /* compiled with other settings than the library */
        fprintf(stderr, "table4: %s\n", qrt_abi_message(why, sizeof why));
        return 1;
    }
    sphere(-0.6, 0.0, 0.0, 0.1);
    if (rc == QRT_OK)
        rc = qrt_planner_add_points(&planner, &points[0][0], K * K);
    /* one plan: only the mask nodes it reads are built */
    if (rc == QRT_OK)
        rc = qrt_planner_plan_now(&planner, &start, &goal, &plan);
    if (rc != QRT_OK) {
        fprintf(stderr, "table4: %s\n", qrt_err_name(rc));
        return 1;
    }
    printf("status %s\n", qrt_plan_status_name(plan.status));
    for (i = 0; i < plan.n_waypoints; i++)
        printf("waypoint %.6f %.6f %.6f\n", plan.waypoints_deg[i][0],
               plan.waypoints_deg[i][1], plan.waypoints_deg[i][2]);
    printf("cost_deg %.6f\n", plan.cost_deg);
    return plan.status == QRT_STATUS_OK ? 0 : 1;
}
