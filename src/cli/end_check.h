/* The exact check of a blocked end (docs/spec.md section Statuses), for
 * hosts that hold the exact points: where the core, holding only merged
 * points, could neither prove a start or goal free nor tell whether it
 * collides, the points as given decide what the plan's detail may say.
 * The CLI streams the scene's points through it, the daemon its picture. */
#ifndef QRT_CLI_END_CHECK_H
#define QRT_CLI_END_CHECK_H

#include <stddef.h>

#include "qrtplan/planner.h"

#ifdef __cplusplus
extern "C" {
#endif

/* Room for end_check_detail's longest sentence. */
#define END_CHECK_DETAIL_LEN 256

struct end_check {
    const struct qrt_planner *pl;
    int n;             /* the blocked end's configurations (IK branches) */
    double q[4][3];    /* each configuration */
    double clear_m[4]; /* its least clearance from the points so far */
};

/* 1 when plan is start_blocked or goal_blocked, its end not proved free
 * (plan->end_free 0), and the core left it unmeasured (plan->end_measured
 * 0: merged points). */
int end_check_needed(const struct qrt_plan *plan);

/* 1 when such an end has been measured (plan->end_measured 1, by the core
 * or by the caller): end_check_detail then gives its sentence. */
int end_check_measured(const struct qrt_plan *plan);

/* Start measuring the blocked end of plan: the configurations of start or
 * goal (of an xyz target, every IK solution within the arm's limits of the
 * branch the target asks for; of a tool tip's, the tip arm's). */
void end_check_begin(struct end_check *c, const struct qrt_planner *pl,
                     const struct qrt_arm *arm, const struct qrt_plan *plan,
                     const struct qrt_target *start,
                     const struct qrt_target *goal);

/* n more exact points (3n doubles). */
void end_check_add(struct end_check *c, const double *xyz, long n);

/* The end's clearance from every point added: its clearest
 * configuration's (<= 0: every configuration collides). */
double end_check_clearance(const struct end_check *c);

/* The detail of a blocked plan whose end was measured (plan->end_measured
 * 1, plan->end_clearance_m the clearance): "collides" only where that is
 * <= 0; else how clear it is, and what kept it from being proved free
 * (the voxel edge under merging, the C-space margin otherwise, and the
 * tool's collision capsule when the arm has a tool). t is the blocked
 * end's target: the IK branch it asks for is named, as the core's details
 * name it. params: the planner's. */
void end_check_detail(const struct qrt_plan *plan, const struct qrt_target *t,
                      const struct qrt_params *params, char *buf, size_t len);

#ifdef __cplusplus
}
#endif
#endif
