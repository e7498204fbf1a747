/* The paper's Table 4 plan on the board: the scene is built in
 * (table4_scene.h, generated from scenes/table4_one_sphere.json), planned
 * with the core exactly as the host's `qrtplan plan` does, and printed with
 * every double in full (%.17g) so that run.sh can compare it with the
 * host's plan bit for bit. Exit 0 when the plan is ok. */
#include <stdint.h>
#include <stdio.h>

#include "qrtplan/qrtplan.h"
#include "table4_scene.h"

static struct qrt_planner pl; /* the whole state: .bss */
static struct qrt_plan plan;  /* (one: the small profile's 512 KiB) */

extern unsigned long mps2_stack_used(void); /* startup.c */
extern uint32_t __stack_bottom__, __stack_top__;

int main(void)
{
    struct qrt_params prm;
    struct qrt_target s = {
        QRT_TARGET_JOINTS, {0, 0, 0}, {QRT_FACING_ANY, QRT_ELBOW_ANY}};
    struct qrt_target g = {
        QRT_TARGET_JOINTS, {0, 0, 0}, {QRT_FACING_ANY, QRT_ELBOW_ANY}};
    int i, rc;
    qrt_params_default(&prm);
    prm.grid_deg = SCENE_GRID_DEG;
    for (i = 0; i < 3; i++) {
        s.value[i] = scene_start[i];
        g.value[i] = scene_goal[i];
    }
    printf("mps2-an500: state %lu bytes, grid %g deg, %d points\n",
           (unsigned long)sizeof pl, SCENE_GRID_DEG, SCENE_N_POINTS);
    if ((rc = qrt_planner_init(&pl, &prm)) != QRT_OK ||
        (rc = qrt_planner_add_points(&pl, &scene_points[0][0],
                                     SCENE_N_POINTS)) != QRT_OK ||
        (rc = qrt_planner_build_mask(&pl)) != QRT_OK ||
        (rc = qrt_planner_plan(&pl, &s, &g, &plan)) != QRT_OK) {
        printf("error %s\n", qrt_err_name(rc));
        return 1;
    }
    printf("status %s\n", qrt_plan_status_name(plan.status));
    printf("cells_blocked %ld\n", plan.cells_blocked);
    printf("nodes_expanded %ld\n", plan.nodes_expanded);
    printf("cost_deg %.17g\n", plan.cost_deg);
    for (i = 0; i < plan.n_waypoints; i++)
        printf("waypoint %.17g %.17g %.17g\n", plan.waypoints_deg[i][0],
               plan.waypoints_deg[i][1], plan.waypoints_deg[i][2]);
    /* the same plan with only the nodes it reads (the core's deepest
     * stack path), which must equal the host's too */
    if ((rc = qrt_planner_plan_now(&pl, &s, &g, &plan)) != QRT_OK) {
        printf("error %s\n", qrt_err_name(rc));
        return 1;
    }
    printf("now_status %s\n", qrt_plan_status_name(plan.status));
    printf("now_nodes_expanded %ld\n", plan.nodes_expanded);
    printf("now_cost_deg %.17g\n", plan.cost_deg);
    for (i = 0; i < plan.n_waypoints; i++)
        printf("now_waypoint %.17g %.17g %.17g\n", plan.waypoints_deg[i][0],
               plan.waypoints_deg[i][1], plan.waypoints_deg[i][2]);
    printf("stack_used %lu of %lu\n", mps2_stack_used(),
           (unsigned long)((const char *)&__stack_top__ -
                           (const char *)&__stack_bottom__));
    return plan.status == QRT_STATUS_OK ? 0 : 1;
}
