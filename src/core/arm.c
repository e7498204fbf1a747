/* Kinematics of the paper's arm (docs/spec.md sections Arm, Kinematics). */
#include "qrtplan/arm.h"

#include <math.h>

#include "geom.h"
#include "qrtplan/status.h"

void qrt_arm_default(struct qrt_arm *arm)
{
    static const double links[3] = QRT_ARM_DEFAULT_LINK_M;
    static const double limits[3][2] = QRT_ARM_DEFAULT_LIMIT_DEG;
    int i;
    for (i = 0; i < 3; i++) {
        arm->link_m[i] = links[i];
        arm->link_radius_m[i] = QRT_ARM_DEFAULT_LINK_RADIUS_M;
        arm->limit_deg[i][0] = limits[i][0];
        arm->limit_deg[i][1] = limits[i][1];
    }
    arm->tool_m = 0.0;
    arm->tool_radius_m = 0.0;
}

int qrt_arm_validate(const struct qrt_arm *arm)
{
    int i;
    for (i = 0; i < 3; i++) {
        double lo = arm->limit_deg[i][0], hi = arm->limit_deg[i][1];
        if (!isfinite(arm->link_m[i]) || arm->link_m[i] <= 0.0 ||
            arm->link_m[i] > 100.0)
            return QRT_E_INVALID;
        if (!isfinite(arm->link_radius_m[i]) || arm->link_radius_m[i] < 0.0 ||
            arm->link_radius_m[i] > 10.0)
            return QRT_E_INVALID;
        if (!isfinite(lo) || !isfinite(hi) || lo > hi)
            return QRT_E_INVALID;
        if (lo < -360.0 || hi > 360.0)
            return QRT_E_INVALID;
    }
    if (arm->limit_deg[0][0] < -180.0 || arm->limit_deg[0][1] > 180.0)
        return QRT_E_INVALID;
    if (!isfinite(arm->tool_m) || arm->tool_m < 0.0 || arm->tool_m > 100.0)
        return QRT_E_INVALID;
    if (!isfinite(arm->tool_radius_m) || arm->tool_radius_m < 0.0 ||
        arm->tool_radius_m > 10.0)
        return QRT_E_INVALID;
    /* one way to say "no tool": length 0 and radius 0 */
    if (arm->tool_m == 0.0 && arm->tool_radius_m > 0.0)
        return QRT_E_INVALID;
    return QRT_OK;
}

void qrt_arm_tip_arm(const struct qrt_arm *arm, struct qrt_arm *tip_arm)
{
    *tip_arm = *arm;
    tip_arm->link_m[2] = arm->link_m[2] + arm->tool_m;
    tip_arm->tool_m = 0.0;
    tip_arm->tool_radius_m = 0.0;
}

void qrt_arm_collision_arm(const struct qrt_arm *arm,
                           struct qrt_arm *collision_arm)
{
    qrt_arm_tip_arm(arm, collision_arm);
    /* the tool's capsule (Pe to the tip) and link 3's (P2 to Pe) both lie
     * in the capsule from P2 to the tip with the larger radius */
    if (arm->tool_m > 0.0 && arm->tool_radius_m > arm->link_radius_m[2])
        collision_arm->link_radius_m[2] = arm->tool_radius_m;
}

double qrt_arm_reach_m(const struct qrt_arm *arm)
{
    struct qrt_arm c;
    double rmax = 0.0;
    int k;
    qrt_arm_collision_arm(arm, &c);
    for (k = 0; k < 3; k++)
        if (c.link_radius_m[k] > rmax)
            rmax = c.link_radius_m[k];
    return c.link_m[0] + c.link_m[1] + c.link_m[2] + rmax;
}

void qrt_arm_tool_tip(const struct qrt_arm *arm, const double joints_deg[3],
                      double tip_m[3])
{
    struct qrt_arm t;
    double p[4][3];
    qrt_arm_tip_arm(arm, &t);
    qrt_arm_fk(&t, joints_deg, p);
    tip_m[0] = p[3][0];
    tip_m[1] = p[3][1];
    tip_m[2] = p[3][2];
}

int qrt_arm_alpha_wraps(const struct qrt_arm *arm)
{
    return qrt_alpha_wraps(arm->limit_deg[0]);
}

int qrt_arm_check_joints(const struct qrt_arm *arm, const double joints_deg[3])
{
    int i;
    for (i = 0; i < 3; i++)
        if (!isfinite(joints_deg[i]))
            return QRT_E_INVALID;
    for (i = 0; i < 3; i++)
        if (joints_deg[i] < arm->limit_deg[i][0] ||
            joints_deg[i] > arm->limit_deg[i][1])
            return QRT_E_LIMITS;
    return QRT_OK;
}

void qrt_arm_fk(const struct qrt_arm *arm, const double joints_deg[3],
                double p[4][3])
{
    double a = joints_deg[0] * QRT_DEG, s = joints_deg[1] * QRT_DEG;
    double e = joints_deg[2] * QRT_DEG;
    double ca = cos(a), sa = sin(a);
    double r2 = arm->link_m[1] * cos(s), z2 = arm->link_m[1] * sin(s);
    double r3 = arm->link_m[2] * cos(s + e), z3 = arm->link_m[2] * sin(s + e);
    p[0][0] = p[0][1] = p[0][2] = 0.0;
    p[1][0] = arm->link_m[0] * ca;
    p[1][1] = arm->link_m[0] * sa;
    p[1][2] = 0.0;
    p[2][0] = p[1][0] + r2 * ca;
    p[2][1] = p[1][1] + r2 * sa;
    p[2][2] = z2;
    p[3][0] = p[2][0] + r3 * ca;
    p[3][1] = p[2][1] + r3 * sa;
    p[3][2] = z2 + z3;
}

/* Planar two-link IK for the point (u, z) seen from the shoulder; writes up
 * to two (sigma, eta) pairs in degrees, and the sign of each eta in
 * eta_sign (+1, -1, or 0 for a straight or folded arm, where both branches
 * coincide and one pair is written). */
static int ik_planar(double l2, double l3, double u, double z, double out[2][2],
                     int eta_sign[2])
{
    double d2 = u * u + z * z;
    double c = (d2 - l2 * l2 - l3 * l3) / (2.0 * l2 * l3);
    double eta, sigma;
    int k, n = 0;
    if (c > 1.0 + 1e-12 || c < -1.0 - 1e-12)
        return 0;
    if (c > 1.0)
        c = 1.0;
    if (c < -1.0)
        c = -1.0;
    for (k = 0; k < 2; k++) {
        eta = (k == 0 ? 1.0 : -1.0) * acos(c);
        sigma = atan2(z, u) - atan2(l3 * sin(eta), l2 + l3 * cos(eta));
        out[n][0] = qrt_wrap_rad(sigma) / QRT_DEG;
        out[n][1] = qrt_wrap_rad(eta) / QRT_DEG;
        eta_sign[n] = k == 0 ? 1 : -1;
        n++;
        if (c == 1.0 || c == -1.0) {
            eta_sign[0] = 0; /* sin(eta) = 0: P2 on the line P1-Pe */
            break;           /* both branches coincide */
        }
    }
    return n;
}

/* The elbow of a planar solution: above the line P1-Pe exactly when
 * u sin(eta) < 0 (the cross product of P1->Pe and P1->P2 is
 * -L2 L3 sin(eta), and "above" is its side to the left of P1->Pe where Pe
 * lies ahead of the shoulder, u > 0, and to the right where it lies
 * behind). */
static enum qrt_ik_elbow elbow_of(double u, int eta_sign)
{
    if (u == 0.0 || eta_sign == 0)
        return QRT_ELBOW_BOTH;
    return (u > 0.0) == (eta_sign < 0) ? QRT_ELBOW_UP : QRT_ELBOW_DOWN;
}

int qrt_arm_ik_branches(const struct qrt_arm *arm, const double xyz_m[3],
                        double alpha_hint_deg, double sol_deg[4][3],
                        struct qrt_ik_branch branch_of[4])
{
    double rho = hypot(xyz_m[0], xyz_m[1]);
    double phi =
        rho > 0.0 ? atan2(xyz_m[1], xyz_m[0]) / QRT_DEG : alpha_hint_deg;
    int side, n = 0;
    for (side = 0; side < 2; side++) {
        /* alpha toward the point (u = rho - L1) or away (u = -rho - L1) */
        double alpha = qrt_wrap_deg(phi + (side ? 180.0 : 0.0));
        double u = (side ? -rho : rho) - arm->link_m[0];
        double pl[2][2];
        int eta_sign[2];
        int k, m = ik_planar(arm->link_m[1], arm->link_m[2], u, xyz_m[2], pl,
                             eta_sign);
        for (k = 0; k < m; k++) {
            double q[3];
            q[0] = alpha;
            q[1] = pl[k][0];
            q[2] = pl[k][1];
            if (alpha == -180.0 && qrt_arm_alpha_wraps(arm))
                q[0] = 180.0;
            if (qrt_arm_check_joints(arm, q) == QRT_OK) {
                sol_deg[n][0] = q[0];
                sol_deg[n][1] = q[1];
                sol_deg[n][2] = q[2];
                /* on the base axis every alpha faces the point alike */
                branch_of[n].facing = rho == 0.0 ? QRT_FACING_BOTH
                                      : side     ? QRT_FACING_BACK
                                                 : QRT_FACING_FRONT;
                branch_of[n].elbow = elbow_of(u, eta_sign[k]);
                n++;
            }
        }
        if (rho == 0.0 && arm->link_m[0] == 0.0)
            break;
    }
    return n;
}

int qrt_arm_ik(const struct qrt_arm *arm, const double xyz_m[3],
               double alpha_hint_deg, double sol_deg[4][3])
{
    struct qrt_ik_branch branch_of[4];
    return qrt_arm_ik_branches(arm, xyz_m, alpha_hint_deg, sol_deg, branch_of);
}

int qrt_ik_branch_check(const struct qrt_ik_branch *request)
{
    int facing = (int)request->facing, elbow = (int)request->elbow;
    if (facing < QRT_FACING_ANY || facing > QRT_FACING_BACK)
        return QRT_E_INVALID;
    if (elbow < QRT_ELBOW_ANY || elbow > QRT_ELBOW_DOWN)
        return QRT_E_INVALID;
    return QRT_OK;
}

int qrt_ik_branch_allows(const struct qrt_ik_branch *request,
                         const struct qrt_ik_branch *solution)
{
    /* one side is a bit, BOTH both bits: a shared bit is a shared side */
    int facing_ok = request->facing == QRT_FACING_ANY ||
                    ((int)request->facing & (int)solution->facing) != 0;
    int elbow_ok = request->elbow == QRT_ELBOW_ANY ||
                   ((int)request->elbow & (int)solution->elbow) != 0;
    return facing_ok && elbow_ok;
}

const char *qrt_ik_facing_name(enum qrt_ik_facing facing)
{
    switch (facing) {
    case QRT_FACING_ANY:
        return "any";
    case QRT_FACING_FRONT:
        return "front";
    case QRT_FACING_BACK:
        return "back";
    case QRT_FACING_BOTH:
        return "both";
    }
    return "unknown";
}

const char *qrt_ik_elbow_name(enum qrt_ik_elbow elbow)
{
    switch (elbow) {
    case QRT_ELBOW_ANY:
        return "any";
    case QRT_ELBOW_UP:
        return "up";
    case QRT_ELBOW_DOWN:
        return "down";
    case QRT_ELBOW_BOTH:
        return "both";
    }
    return "unknown";
}

double qrt_arm_joint_distance(const struct qrt_arm *arm, const double a_deg[3],
                              const double b_deg[3])
{
    double d0 = b_deg[0] - a_deg[0];
    double d1 = b_deg[1] - a_deg[1], d2 = b_deg[2] - a_deg[2];
    if (qrt_arm_alpha_wraps(arm))
        d0 = qrt_wrap_deg(d0);
    return sqrt(d0 * d0 + d1 * d1 + d2 * d2);
}
