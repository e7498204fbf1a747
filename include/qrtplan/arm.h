/* The paper's 3-DoF arm: geometry, joint limits, forward and inverse
 * kinematics (docs/spec.md sections Arm, Kinematics). Angles are degrees at
 * this interface. */
#ifndef QRTPLAN_ARM_H
#define QRTPLAN_ARM_H

#include "qrtplan/joints.h"

#ifdef __cplusplus
extern "C" {
#endif

enum { QRT_ALPHA = 0, QRT_SIGMA = 1, QRT_ETA = 2 };

/* The default arm's links (docs/spec.md section Arm) as initializers, for
 * qrt_arm_default; its limits are QRT_ARM_DEFAULT_LIMIT_DEG. */
#define QRT_ARM_DEFAULT_LINK_M                                                 \
    {                                                                          \
        0.090, 0.332, 0.538                                                    \
    }
#define QRT_ARM_DEFAULT_LINK_RADIUS_M 0.02

struct qrt_arm {
    double link_m[3];        /* L1, L2, L3 */
    double link_radius_m[3]; /* capsule radius of each link */
    double limit_deg[3][2];  /* [joint][lo, hi]; alpha wraps iff [-180, 180] */
};

/* The default arm: the links above (Table 1 of the paper, radii 0.02 m) and
 * QRT_ARM_DEFAULT_LIMIT_DEG. */
void qrt_arm_default(struct qrt_arm *arm);

/* QRT_OK, or QRT_E_INVALID for non-finite, negative or zero lengths,
 * negative radii, or inverted or out-of-range limits. */
int qrt_arm_validate(const struct qrt_arm *arm);

/* True when alpha's limits are the full circle, so alpha wraps. */
int qrt_arm_alpha_wraps(const struct qrt_arm *arm);

/* QRT_OK if joints_deg is finite and inside the limits (alpha may be given
 * anywhere in [-180, 180] when it wraps), QRT_E_INVALID or QRT_E_LIMITS. */
int qrt_arm_check_joints(const struct qrt_arm *arm, const double joints_deg[3]);

/* Joint positions P0, P1, P2, Pe in metres for joints in degrees. */
void qrt_arm_fk(const struct qrt_arm *arm, const double joints_deg[3],
                double p[4][3]);

/* Every inverse-kinematics solution for end-effector point xyz_m that lies
 * inside the joint limits: at most 4 (alpha toward or away from the point,
 * elbow up or down). Returns the count written to sol_deg. A point on the
 * base axis has every alpha as a solution; then alpha_hint_deg is used. */
int qrt_arm_ik(const struct qrt_arm *arm, const double xyz_m[3],
               double alpha_hint_deg, double sol_deg[4][3]);

/* Joint-space distance in degrees (Euclidean, alpha the short way round when
 * it wraps), the metric of plan costs. */
double qrt_arm_joint_distance(const struct qrt_arm *arm, const double a_deg[3],
                              const double b_deg[3]);

#ifdef __cplusplus
}
#endif
#endif
