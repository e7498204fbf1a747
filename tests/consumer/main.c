/* A project outside qrtplan that links the installed core, as a user
 * would: plans around one point behind the arm. It is compiled without -D
 * flags of its own, so the settings it sees are those the installed
 * package gives it; qrt_planner_init refuses any that are not the
 * library's. */
#include <stdio.h>

#include "qrtplan/qrtplan.h"

static struct qrt_planner pl;

int main(void)
{
    struct qrt_params prm;
    struct qrt_plan plan;
    struct qrt_target s = {
        QRT_TARGET_JOINTS, {-100, 0, 0}, {QRT_FACING_ANY, QRT_ELBOW_ANY}};
    struct qrt_target g = {
        QRT_TARGET_JOINTS, {100, 0, 0}, {QRT_FACING_ANY, QRT_ELBOW_ANY}};
    double point[3] = {-0.6, 0.0, 0.0};
    qrt_params_default(&prm);
    if (prm.grid_deg < QRT_GRID_DEG_MIN) /* a library built for coarser */
        prm.grid_deg = QRT_GRID_DEG_MIN;
    printf("settings: QRT_GRID_DEG_MIN %d QRT_MAX_POINTS %ld "
           "QRT_MAX_WAYPOINTS %d QRT_GOAL_REGION_NODES %d "
           "QRT_LAZY_INDEX_AFTER %d\n",
           (int)QRT_GRID_DEG_MIN, (long)QRT_MAX_POINTS, (int)QRT_MAX_WAYPOINTS,
           (int)QRT_GOAL_REGION_NODES, (int)QRT_LAZY_INDEX_AFTER);
    if (qrt_planner_init(&pl, &prm) != QRT_OK ||
        qrt_planner_add_points(&pl, point, 1) != QRT_OK ||
        qrt_planner_build_mask(&pl) != QRT_OK ||
        qrt_planner_plan(&pl, &s, &g, &plan) != QRT_OK) {
        char why[QRT_ABI_MESSAGE_LEN];
        printf("refused: %s\n", qrt_abi_message(why, sizeof why));
        return 1;
    }
    printf("%s, %d waypoints\n", qrt_plan_status_name(plan.status),
           plan.n_waypoints);
    return plan.status == QRT_STATUS_OK && plan.n_waypoints >= 2 ? 0 : 1;
}
