/* A project outside qrtplan that links the installed core, as a user
 * would: plans around one point behind the arm. */
#include <stdio.h>

#include "qrtplan/qrtplan.h"

static struct qrt_planner pl;

int main(void)
{
    struct qrt_params prm;
    struct qrt_plan plan;
    struct qrt_target s = {QRT_TARGET_JOINTS, {-100, 0, 0}};
    struct qrt_target g = {QRT_TARGET_JOINTS, {100, 0, 0}};
    double point[3] = {-0.6, 0.0, 0.0};
    qrt_params_default(&prm);
    if (qrt_planner_init(&pl, &prm) != QRT_OK ||
        qrt_planner_add_points(&pl, point, 1) != QRT_OK ||
        qrt_planner_build_mask(&pl) != QRT_OK ||
        qrt_planner_plan(&pl, &s, &g, &plan) != QRT_OK)
        return 1;
    printf("%s, %d waypoints\n", qrt_plan_status_name(plan.status),
           plan.n_waypoints);
    return plan.status == QRT_STATUS_OK && plan.n_waypoints >= 2 ? 0 : 1;
}
