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
    /* A tool on link 3 (docs/spec.md section Arm, Tool): a fourth capsule
     * of radius tool_radius_m from the end effector Pe to the tool tip
     * Pe + tool_m * unit(Pe - P2), collinear with link 3. 0 and 0: no
     * tool. */
    double tool_m;
    double tool_radius_m;
};

/* The default arm: the links above (Table 1 of the paper, radii 0.02 m),
 * QRT_ARM_DEFAULT_LIMIT_DEG and no tool. */
void qrt_arm_default(struct qrt_arm *arm);

/* QRT_OK, or QRT_E_INVALID for non-finite, negative or zero lengths,
 * negative radii, inverted or out-of-range limits, a tool length or radius
 * that is not finite or is negative (length at most 100 m, radius at most
 * 10 m), or a tool radius without a tool length (a tool of length 0 is no
 * tool). */
int qrt_arm_validate(const struct qrt_arm *arm);

/* The same arm with the tool tip as its end effector: link 3 lengthened by
 * the tool (collinear with it, so the joints that put this arm's Pe at a
 * point put the first arm's tool tip there), and no tool. Without a tool,
 * a copy. */
void qrt_arm_tip_arm(const struct qrt_arm *arm, struct qrt_arm *tip_arm);

/* The arm the planner checks collisions with (docs/spec.md section
 * Collision), the one place it is derived: qrt_arm_tip_arm, with link 3's
 * radius the larger of link 3's and the tool's. Its link-3 capsule holds
 * both link 3's and the tool's, so it is never less than the arm with its
 * tool. Without a tool, a copy. */
void qrt_arm_collision_arm(const struct qrt_arm *arm,
                           struct qrt_arm *collision_arm);

/* How far from the base origin any point of the arm's surface (links and
 * tool) can lie: L1 + L2 + L3 + tool_m plus the largest radius. */
double qrt_arm_reach_m(const struct qrt_arm *arm);

/* The tool tip in metres for joints in degrees (Pe without a tool). */
void qrt_arm_tool_tip(const struct qrt_arm *arm, const double joints_deg[3],
                      double tip_m[3]);

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

/* IK branches (docs/spec.md section Kinematics, Branches). Facing: front
 * when alpha points at the target, (x, y) . (cos alpha, sin alpha) > 0;
 * back when it points away, < 0. Elbow, in the arm's vertical plane with u
 * the end effector's horizontal offset from the shoulder P1 along alpha:
 * up when the elbow P2 lies above (on the +z side of) the line P1-Pe,
 * which is u sin(eta) < 0; down when u sin(eta) > 0. A solution for which
 * the product is zero (a straight or folded arm, or the end effector
 * straight above or below the shoulder), or whose point is on the base axis
 * (rho = 0, facing), is both. As a request, a field is ANY, or one side
 * (FRONT/BACK, UP/DOWN); as the branch of a solution, one side or BOTH
 * (FRONT | BACK, UP | DOWN), never ANY. The values are those of the daemon's
 * plan_request_t and plan_t. */
enum qrt_ik_facing {
    QRT_FACING_ANY = 0,
    QRT_FACING_FRONT = 1,
    QRT_FACING_BACK = 2,
    QRT_FACING_BOTH = 3
};
enum qrt_ik_elbow {
    QRT_ELBOW_ANY = 0,
    QRT_ELBOW_UP = 1,
    QRT_ELBOW_DOWN = 2,
    QRT_ELBOW_BOTH = 3
};
struct qrt_ik_branch {
    enum qrt_ik_facing facing;
    enum qrt_ik_elbow elbow;
};

/* qrt_arm_ik, with the branch of each solution in branch_of[i]. */
int qrt_arm_ik_branches(const struct qrt_arm *arm, const double xyz_m[3],
                        double alpha_hint_deg, double sol_deg[4][3],
                        struct qrt_ik_branch branch_of[4]);

/* QRT_OK when *request is a request (each field ANY or one side), else
 * QRT_E_INVALID (BOTH, or a value outside the enums). */
int qrt_ik_branch_check(const struct qrt_ik_branch *request);

/* True when a solution of branch *solution may be used for *request: each
 * field of the request is ANY or shared with the solution's. */
int qrt_ik_branch_allows(const struct qrt_ik_branch *request,
                         const struct qrt_ik_branch *solution);

/* "any", "front", "back", "both" / "any", "up", "down", "both": the names
 * of scene and plan files; "unknown" outside the enums. */
const char *qrt_ik_facing_name(enum qrt_ik_facing facing);
const char *qrt_ik_elbow_name(enum qrt_ik_elbow elbow);

/* Joint-space distance in degrees (Euclidean, alpha the short way round when
 * it wraps), the metric of plan costs. */
double qrt_arm_joint_distance(const struct qrt_arm *arm, const double a_deg[3],
                              const double b_deg[3]);

#ifdef __cplusplus
}
#endif
#endif
