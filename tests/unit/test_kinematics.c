/* Forward and inverse kinematics over the whole joint range, and the
 * paper's collision-angle equations (Eqs. 1-11) against brute force and
 * against the mask. */
#include "check.h"
#include "qrtplan/joints.h"
#include "qrtplan/qrtplan.h"
#include "ref_arm.h"

#define PI 3.14159265358979323846
#define DEG (PI / 180.0)

static struct qrt_planner pl;

static void test_fk_matches_reference(const struct qrt_arm *arm)
{
    int i, k, j;
    for (i = 0; i < test_count(2000); i++) {
        double q[3], p[4][3], r[4][3], err = 0.0;
        for (j = 0; j < 3; j++)
            q[j] = test_uniform(arm->limit_deg[j][0], arm->limit_deg[j][1]);
        qrt_arm_fk(arm, q, p);
        ref_fk(q, r);
        for (k = 0; k < 4; k++)
            for (j = 0; j < 3; j++)
                err = fmax(err, fabs(p[k][j] - r[k][j]));
        CHECK(err < 1e-12, "fk differs by %g at (%g %g %g)", err, q[0], q[1],
              q[2]);
    }
    {
        double zero[3] = {0, 0, 0}, p[4][3];
        qrt_arm_fk(arm, zero, p);
        CHECK(fabs(p[3][0] - 0.960) < 1e-12 && fabs(p[3][2]) < 1e-12,
              "straight arm reach %g", p[3][0]);
    }
}

/* IK of FK(q) must contain q (every branch considered), and every solution
 * must reach the point. */
static void test_ik_round_trip(const struct qrt_arm *arm)
{
    int i, j, s, found_total = 0;
    for (i = 0; i < test_count(20000); i++) {
        double q[3], p[4][3], sols[4][3];
        int n, found = 0;
        for (j = 0; j < 3; j++)
            q[j] = test_uniform(arm->limit_deg[j][0], arm->limit_deg[j][1]);
        qrt_arm_fk(arm, q, p);
        n = qrt_arm_ik(arm, p[3], q[0], sols);
        CHECK(n >= 1 && n <= 4, "ik gave %d solutions", n);
        for (s = 0; s < n; s++) {
            double r[4][3], e = 0.0;
            qrt_arm_fk(arm, sols[s], r);
            for (j = 0; j < 3; j++)
                e = fmax(e, fabs(r[3][j] - p[3][j]));
            CHECK(e < 1e-9, "ik solution misses by %g m", e);
            CHECK(qrt_arm_check_joints(arm, sols[s]) == QRT_OK,
                  "ik solution outside limits");
            if (qrt_arm_joint_distance(arm, sols[s], q) < 1e-6)
                found = 1;
        }
        /* q itself is found unless the elbow is (nearly) straight, where
         * the two branches meet and rounding picks one */
        if (fabs(q[2]) > 1e-3 && fabs(fabs(q[2]) - 180.0) > 1e-3)
            CHECK(found, "ik lost (%g %g %g)", q[0], q[1], q[2]);
        found_total += found;
    }
    CHECK(found_total > test_count(20000) * 995 / 1000, "round trips %d",
          found_total);
    {
        double far[3] = {2.0, 0.0, 0.0}, sols[4][3];
        CHECK(qrt_arm_ik(arm, far, 0.0, sols) == 0, "out of reach point");
    }
}

/* The paper's Eqs. 6-11 give, for a point and a length l along link 3,
 * the (sigma, eta) that put that spot of link 3 on the point (alpha from
 * Eq. 1). Check each such configuration touches the point (reference FK)
 * and that its lattice node is blocked in the mask. */
static void test_paper_equations(void)
{
    struct qrt_params prm;
    int i, checked = 0;
    qrt_params_default(&prm);
    for (i = 0; i < test_count(300); i++) {
        double rho = test_uniform(0.25, 0.9), phi = test_uniform(-PI, PI);
        double p[3], l1 = REF_L[0], l2 = REF_L[1];
        double a, r1, th1, th2, th3, l;
        int side;
        p[0] = rho * cos(phi);
        p[1] = rho * sin(phi);
        p[2] = test_uniform(-0.4, 0.6);
        a = atan2(p[1], p[0]); /* Eq. 1 */
        r1 = sqrt(pow(sqrt(p[0] * p[0] + p[1] * p[1]) - l1, 2) +
                  p[2] * p[2]);                                  /* Eq. 6 */
        th1 = atan2(p[2], sqrt(p[0] * p[0] + p[1] * p[1]) - l1); /* Eq. 7 */
        qrt_planner_init(&pl, &prm);
        qrt_planner_add_points(&pl, p, 1);
        qrt_planner_build_mask(&pl);
        for (l = 0.05; l <= REF_L[2]; l += 0.05) {
            double c2 = (l2 * l2 + r1 * r1 - l * l) / (2 * l2 * r1);
            double c3 = (l2 * l2 + l * l - r1 * r1) / (2 * l2 * l);
            if (fabs(c2) > 1.0 || fabs(c3) > 1.0)
                continue;
            th2 = acos(c2); /* Eq. 8 */
            th3 = acos(c3); /* Eq. 9 */
            for (side = 0; side < 2; side++) {
                /* Eq. 10: Sigma = th1 +- th2, H = -+(pi - th3) */
                double q[3], fk[4][3], d, dir[3], spot[3];
                int j, ijk[3];
                q[0] = a / DEG;
                q[1] = (side ? th1 - th2 : th1 + th2) / DEG;
                q[2] = (side ? PI - th3 : th3 - PI) / DEG;
                if (q[1] < -40.0 || q[1] > 180.0 || q[2] < -180.0 ||
                    q[2] > 140.0)
                    continue;
                ref_fk(q, fk);
                for (j = 0; j < 3; j++) {
                    dir[j] = (fk[3][j] - fk[2][j]) / REF_L[2];
                    spot[j] = fk[2][j] + l * dir[j];
                }
                d = sqrt(pow(spot[0] - p[0], 2) + pow(spot[1] - p[1], 2) +
                         pow(spot[2] - p[2], 2));
                CHECK(d < 1e-9, "Eqs. 6-10 miss the point by %g m", d);
                for (j = 0; j < 3; j++)
                    ijk[j] = (int)floor((q[j] - pl.mask.lat.lo_deg[j]) /
                                            pl.mask.lat.grid_deg +
                                        0.5);
                ijk[0] %= pl.mask.lat.n[0];
                CHECK(qrt_mask_blocked(&pl.mask, ijk),
                      "node of a colliding configuration (%g %g %g) is free",
                      q[0], q[1], q[2]);
                checked++;
            }
        }
    }
    CHECK(checked > test_count(500), "only %d paper configurations checked",
          checked);
}

/* alpha wraps exactly when its limits are the whole circle, and a wrapping
 * alpha's angles reduce to (-180, 180]: both from qrtplan/joints.h, which
 * the CAN master and the simulated drives share with the core. */
static void test_alpha_wrap(void)
{
    static const double limits[][2] = {{-180.0, 180.0},
                                       {-180.0, 175.0},
                                       {-175.0, 180.0},
                                       {-180.0, 179.999},
                                       {-90.0, 90.0}};
    static const double wrap[][2] = {
        {180.0, 180.0},  {-180.0, 180.0}, {190.0, -170.0}, {540.0, 180.0},
        {-540.0, 180.0}, {359.5, -0.5},   {-0.25, -0.25},  {-179.5, -179.5}};
    struct qrt_arm arm;
    size_t i;
    qrt_arm_default(&arm);
    for (i = 0; i < sizeof limits / sizeof limits[0]; i++) {
        int want = i == 0;
        arm.limit_deg[0][0] = limits[i][0];
        arm.limit_deg[0][1] = limits[i][1];
        CHECK(qrt_alpha_wraps(limits[i]) == want &&
                  qrt_arm_alpha_wraps(&arm) == want,
              "alpha in [%g, %g] %s", limits[i][0], limits[i][1],
              want ? "wraps" : "does not wrap");
    }
    for (i = 0; i < sizeof wrap / sizeof wrap[0]; i++)
        CHECK(qrt_wrap_deg(wrap[i][0]) == wrap[i][1], "wrap %g gave %g, not %g",
              wrap[i][0], qrt_wrap_deg(wrap[i][0]), wrap[i][1]);
}

int main(void)
{
    struct qrt_arm arm;
    test_seed(777);
    qrt_arm_default(&arm);
    CHECK(qrt_arm_validate(&arm) == QRT_OK, "default arm valid");
    test_fk_matches_reference(&arm);
    test_ik_round_trip(&arm);
    test_paper_equations();
    test_alpha_wrap();
    {
        double bad[3] = {0, -41, 0}, nan_q[3] = {NAN, 0, 0};
        CHECK(qrt_arm_check_joints(&arm, bad) == QRT_E_LIMITS, "limits");
        CHECK(qrt_arm_check_joints(&arm, nan_q) == QRT_E_INVALID, "nan");
        arm.link_m[1] = -1.0;
        CHECK(qrt_arm_validate(&arm) == QRT_E_INVALID, "negative link");
    }
    return test_done("test_kinematics");
}
