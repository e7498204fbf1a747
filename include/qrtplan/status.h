/* Error codes of the core's functions, the statuses of a plan and of the
 * planner's mask. */
#ifndef QRTPLAN_STATUS_H
#define QRTPLAN_STATUS_H

#ifdef __cplusplus
extern "C" {
#endif

/* Errors: returned by functions whose input is unusable (never for a plan
 * that merely finds no path). Zero is success, errors are negative, in the
 * style of littlefs. */
enum qrt_err {
    QRT_OK = 0,
    QRT_E_INVALID = -1, /* NaN/Inf, wrong sizes, limits inverted, bad grid */
    QRT_E_LIMITS = -2,  /* a joint configuration outside the arm's limits */
    QRT_E_TOO_BIG = -3, /* the scene's lattice is larger than this build */
    QRT_E_ABI = -4      /* the caller was compiled with other settings than
                           the library (qrt_abi_message says which) */
};

/* The outcome of a plan (docs/spec.md section Statuses). */
enum qrt_plan_status {
    QRT_STATUS_OK = 0,
    QRT_STATUS_NO_PATH,
    QRT_STATUS_START_BLOCKED,
    QRT_STATUS_GOAL_BLOCKED,
    QRT_STATUS_UNREACHABLE,
    QRT_STATUS_CAPACITY
};

/* What the planner's mask holds for the points now in its table
 * (qrt_planner_mask_state; the terms are defined in planner.h). */
enum qrt_mask_state {
    QRT_MASK_NONE = 0, /* points only: no mask for these points yet */
    QRT_MASK_PARTIAL,  /* the rows and nodes built as read for these
                          points, and the clusters to build more from */
    QRT_MASK_WHOLE     /* every row built for these points */
};

/* "ok", "no_path", ... exactly as in the plan file format. */
const char *qrt_plan_status_name(enum qrt_plan_status status);
/* A short English description of an error code. */
const char *qrt_err_name(int err);

#ifdef __cplusplus
}
#endif
#endif
