#include "end_check.h"

#include <stdio.h>

/* a blocked end that was not proved free */
static int end_unproven(const struct qrt_plan *plan)
{
    return (plan->status == QRT_STATUS_START_BLOCKED ||
            plan->status == QRT_STATUS_GOAL_BLOCKED) &&
           !plan->end_free;
}

int end_check_needed(const struct qrt_plan *plan)
{
    return end_unproven(plan) && !plan->end_measured;
}

int end_check_measured(const struct qrt_plan *plan)
{
    return end_unproven(plan) && plan->end_measured;
}

void end_check_begin(struct end_check *c, const struct qrt_planner *pl,
                     const struct qrt_arm *arm, const struct qrt_plan *plan,
                     const struct qrt_target *start,
                     const struct qrt_target *goal)
{
    int is_goal = plan->status == QRT_STATUS_GOAL_BLOCKED, i, k;
    const struct qrt_target *t = is_goal ? goal : start;
    const double *reported = is_goal ? plan->goal_deg : plan->start_deg;
    c->pl = pl;
    if (t->kind == QRT_TARGET_JOINTS) {
        c->n = 1;
        for (k = 0; k < 3; k++)
            c->q[0][k] = t->value[k];
    } else {
        /* only the solutions of the branch the target asks for, as the
         * core tries them; the one the plan reports is among them, and
         * its alpha is the hint for a point on the base axis */
        double sols[4][3];
        struct qrt_ik_branch found[4];
        struct qrt_arm tip_arm; /* a tool tip's point: the tip arm's IK */
        int all;
        qrt_arm_tip_arm(arm, &tip_arm);
        all =
            qrt_arm_ik_branches(t->kind == QRT_TARGET_TOOL_TIP ? &tip_arm : arm,
                                t->value, reported[0], sols, found);
        c->n = 0;
        for (i = 0; i < all; i++) {
            if (!qrt_ik_branch_allows(&t->ik, &found[i]))
                continue;
            for (k = 0; k < 3; k++)
                c->q[c->n][k] = sols[i][k];
            c->n++;
        }
    }
    for (i = 0; i < 4; i++)
        c->clear_m[i] = 1e30;
}

void end_check_add(struct end_check *c, const double *xyz, long n)
{
    int i;
    for (i = 0; i < c->n; i++) {
        double d = qrt_planner_clearance(c->pl, c->q[i], xyz, n);
        if (d < c->clear_m[i])
            c->clear_m[i] = d;
    }
}

double end_check_clearance(const struct end_check *c)
{
    double best = c->n > 0 ? c->clear_m[0] : 0.0;
    int i;
    for (i = 1; i < c->n; i++)
        if (c->clear_m[i] > best)
            best = c->clear_m[i];
    return best;
}

/* " facing front with the elbow up" and the like, as the core's details
 * name a requested branch; "" for a request of any branch */
static void branch_phrase(const struct qrt_ik_branch *ik, char *buf, size_t len)
{
    const char *facing =
        ik->facing == QRT_FACING_ANY ? "" : qrt_ik_facing_name(ik->facing);
    snprintf(buf, len, "%s%s%s%s", *facing ? " facing " : "", facing,
             ik->elbow == QRT_ELBOW_ANY ? "" : " with the elbow ",
             ik->elbow == QRT_ELBOW_ANY ? "" : qrt_ik_elbow_name(ik->elbow));
}

void end_check_detail(const struct qrt_plan *plan, const struct qrt_target *t,
                      const struct qrt_params *params, char *buf, size_t len)
{
    const char *end =
        plan->status == QRT_STATUS_GOAL_BLOCKED ? "goal" : "start";
    double mm = 1000.0 * plan->end_clearance_m;
    char branch[48] = "";
    if (t->kind != QRT_TARGET_JOINTS)
        branch_phrase(&t->ik, branch, sizeof branch);
    if (plan->end_clearance_m <= 0.0 && branch[0])
        snprintf(buf, len,
                 "every %s configuration%s collides with obstacle points", end,
                 branch);
    else if (plan->end_clearance_m <= 0.0)
        snprintf(buf, len, "%s configuration collides with obstacle points",
                 end);
    else if (plan->voxel_m > 0.0)
        snprintf(buf, len,
                 "%s%s is clear of the points by %.1f mm beyond the margin, "
                 "but cannot be proved free under point merging (voxel "
                 "%.0f mm)",
                 end, branch, mm, 1000.0 * plan->voxel_m);
    else if (params->arm.tool_m > 0.0)
        snprintf(buf, len,
                 "%s%s is clear of the points by %.1f mm beyond the margin, "
                 "but cannot be proved free within the C-space margin "
                 "(%g deg), the points' float rounding and the tool's "
                 "collision capsule",
                 end, branch, mm, params->cspace_margin_deg);
    else
        snprintf(buf, len,
                 "%s%s is clear of the points by %.1f mm beyond the margin, "
                 "but cannot be proved free within the C-space margin "
                 "(%g deg) and the points' float rounding",
                 end, branch, mm, params->cspace_margin_deg);
}
