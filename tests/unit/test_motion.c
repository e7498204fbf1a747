/* Certified motions: every motion the mask walk or the conservative
 * advancement accepts is free when sampled finely with the reference arm,
 * across the alpha seam too; where the walk fails, the configuration it
 * names collides exactly when the reference arm says so; the clearance
 * equals the reference arm's, wherever in the table the points near the
 * arm lie. Uses the core's internal motion.h. */
#include "../../src/core/motion.h"
#include "check.h"
#include "qrtplan/qrtplan.h"
#include "ref_arm.h"
#include "stored_points.h"

static struct qrt_planner pl;
static float boxes[QRTI_BLOCK_BOXES][6];

static double wrap180(double x)
{
    x = fmod(x, 360.0);
    return x <= -180.0 ? x + 360.0 : (x > 180.0 ? x - 360.0 : x);
}

static double motion_clearance(const double a[3], const double b[3],
                               const double *pts, long n,
                               const double radius[3])
{
    double d[3], worst = 1e30, span;
    int k, steps, j;
    d[0] = wrap180(b[0] - a[0]);
    d[1] = b[1] - a[1];
    d[2] = b[2] - a[2];
    span = fmax(fabs(d[0]), fmax(fabs(d[1]), fabs(d[2])));
    steps = (int)ceil(span / 0.02) + 1;
    for (k = 0; k <= steps; k++) {
        double q[3];
        for (j = 0; j < 3; j++)
            q[j] = a[j] + d[j] * k / steps;
        worst = fmin(worst, ref_clearance(q, pts, n, radius));
    }
    return worst;
}

/* qrt_clearance_capped against the reference clearance: min(clearance,
 * cap) where the arm is clear, <= 0 where it collides, on clouds whose
 * points lie near one link or another among many far from the arm (the
 * boxes that turn points away must never turn away one that counts). */
static void check_clearance(void)
{
    enum { CLOUD = 300 };
    static double cloud[3 * CLOUD];
    static const double caps[4] = {1e30, 0.5, 0.05, 2e-7};
    struct qrt_params prm;
    double radius[3];
    int trial, i, k, clear = 0, colliding = 0, capped = 0;
    qrt_params_default(&prm);
    for (k = 0; k < 3; k++)
        radius[k] = prm.arm.link_radius_m[k] + prm.margin_m;
    for (trial = 0; trial < test_count(300); trial++) {
        double q[3], p[4][3], ref;
        int link = trial % 3, near = trial % 4,
            place = (int)test_uniform(0.0, CLOUD - 3.5); /* the near ones */
        q[0] = test_uniform(-180, 180);
        q[1] = test_uniform(-40, 180);
        q[2] = test_uniform(-180, 140);
        qrt_arm_fk(&prm.arm, q, p);
        for (i = 0; i < CLOUD; i++) {
            double x[3];
            if (i >= place && i < place + near) { /* near a point of one link */
                double t = test_uniform(0, 1), spread = 0.05 + 0.15 * (i % 3);
                for (k = 0; k < 3; k++)
                    x[k] = p[link][k] + t * (p[link + 1][k] - p[link][k]) +
                           test_uniform(-spread, spread);
            } else {
                double rho = test_uniform(0.0, 1.5),
                       phi = test_uniform(-3.1, 3.1);
                x[0] = rho * cos(phi);
                x[1] = rho * sin(phi);
                x[2] = test_uniform(-1.2, 1.2);
            }
            for (k = 0; k < 3; k++)
                cloud[3 * i + k] = x[k];
        }
        qrt_planner_init(&pl, &prm);
        qrt_planner_add_points(&pl, cloud, CLOUD);
        CHECK(pl.points.voxel_m == 0.0, "cloud stored as given");
        /* against the points the table holds (those within reach) */
        stored_points(&pl.points, pl.points.count, cloud);
        ref = ref_clearance(q, cloud, pl.points.count, radius);
        for (k = 0; k < 4; k++) {
            double got =
                qrt_clearance_capped(&prm.arm, radius, &pl.points, q, caps[k]);
            if (ref <= 0.0) {
                CHECK(got <= 0.0, "colliding arm: clearance %g (reference %g)",
                      got, ref);
            } else {
                double want = ref < caps[k] ? ref : caps[k];
                CHECK(fabs(got - want) < 1e-9,
                      "trial %d cap %g: clearance %.12g, reference %.12g",
                      trial, caps[k], got, want);
                capped += ref > caps[k];
            }
        }
        if (ref <= 0.0)
            colliding++;
        else
            clear++;
    }
    printf("clearance: %d clear, %d colliding, %d capped answers\n", clear,
           colliding, capped);
    CHECK(clear >= test_count(300) / 5 && colliding >= test_count(300) / 5,
          "both kinds of arm pose: %d clear, %d colliding", clear, colliding);
}

/* The clearance's boxes, test by test, at their edges: among far points,
 * one point (A) clear of the arm by d1 and another (B) by d2 = d1 - u,
 * u up to 1 cm, each straight out along an axis from the arm's extreme
 * joint that way: B is inside the box that A's clearance leaves by u,
 * and decides the answer. B lies on the first entry of a block
 * of the box test in half the trials. */
static void check_box_edges(void)
{
    enum { EDGE_CLOUD = 300 };
    static double cloud[3 * EDGE_CLOUD];
    struct qrt_params prm;
    double radius[3];
    int trial, i, k;
    qrt_params_default(&prm);
    qrt_planner_init(&pl, &prm);
    for (k = 0; k < 3; k++)
        radius[k] = prm.arm.link_radius_m[k] + prm.margin_m;
    CHECK(radius[0] == radius[1] && radius[1] == radius[2],
          "the test takes one radius for every link");
    for (trial = 0; trial < test_count(600); trial++) {
        /* u under a float's place in half the trials: B then lies on
         * the box's edge, which the box of floats must not cut */
        double q[3], p[4][3], d1 = test_uniform(0.01, 0.2), d2, ref, got;
        int axis = trial % 3, side = trial / 3 % 2 ? 1 : -1, a_at, b_at,
            high = 0, low = 0, j;
        d2 = d1 - (trial / 6 % 2 ? test_uniform(1e-4, 0.01)
                                 : test_uniform(0.0, 4e-8));
        q[0] = test_uniform(-180, 180);
        q[1] = test_uniform(-40, 180);
        q[2] = test_uniform(-180, 140);
        qrt_arm_fk(&prm.arm, q, p);
        for (j = 1; j < 4; j++) { /* the extreme joints along the axis */
            if (p[j][axis] * side > p[high][axis] * side)
                high = j;
            if (p[j][axis] * side < p[low][axis] * side)
                low = j;
        }
        for (i = 0; i < EDGE_CLOUD; i++) { /* 1.3 to 1.6 m out: far */
            double rho = test_uniform(1.3, 1.6), phi = test_uniform(-3.1, 3.1),
                   el = test_uniform(-1.2, 1.2);
            cloud[3 * i] = rho * cos(el) * cos(phi);
            cloud[3 * i + 1] = rho * cos(el) * sin(phi);
            cloud[3 * i + 2] = rho * sin(el);
        }
        a_at = (int)test_uniform(0.0, 63.9);
        b_at = trial % 2 ? 64 * (1 + (int)test_uniform(0.0, 3.99))
                         : 64 + (int)test_uniform(0.0, EDGE_CLOUD - 64.1);
        for (k = 0; k < 3; k++) {
            cloud[3 * a_at + k] = p[low][k];
            cloud[3 * b_at + k] = p[high][k];
        }
        cloud[3 * a_at + axis] -= side * (radius[low ? low - 1 : 0] + d1);
        cloud[3 * b_at + axis] += side * (radius[high ? high - 1 : 0] + d2);
        qrt_points_reset(&pl.points, 10.0); /* the far ones too */
        CHECK(qrt_points_add(&pl.points, cloud, EDGE_CLOUD) == QRT_OK &&
                  pl.points.count == EDGE_CLOUD,
              "every point kept");
        stored_points(&pl.points, EDGE_CLOUD, cloud);
        ref = ref_clearance(q, cloud, EDGE_CLOUD, radius);
        got = qrt_clearance_capped(&prm.arm, radius, &pl.points, q, 1e30);
        CHECK(fabs(ref - d2) < 1e-6, "trial %d: B is %.9g clear, not %.9g",
              trial, ref, d2);
        CHECK(fabs(got - ref) < 1e-9,
              "trial %d: clearance %.12g, reference %.12g (B at %d, axis "
              "%d, side %d)",
              trial, got, ref, b_at, axis, side);
    }
}

int main(void)
{
    struct qrt_params prm;
    double pts[3 * 12], radius[3];
    int trial, accepted_mask = 0, accepted_exact = 0, collided_at = 0, i, k;
    test_seed(31337);
    for (trial = 0; trial < test_count(40); trial++) {
        int n = 2 + trial % 10;
        qrt_params_default(&prm);
        qrt_planner_init(&pl, &prm);
        for (i = 0; i < n; i++) {
            double rho = test_uniform(0.2, 0.95), phi = test_uniform(-3.1, 3.1);
            pts[3 * i] = rho * cos(phi);
            pts[3 * i + 1] = rho * sin(phi);
            pts[3 * i + 2] = test_uniform(-0.4, 0.6);
        }
        qrt_planner_add_points(&pl, pts, n);
        qrt_planner_build_mask(&pl);
        qrt_points_block_boxes(&pl.points, boxes);
        for (k = 0; k < 3; k++)
            radius[k] = prm.arm.link_radius_m[k] + prm.margin_m;
        for (i = 0; i < 200; i++) {
            double a[3], b[3], len = i % 2 ? 8.0 : 60.0;
            a[0] = test_uniform(-180, 180);
            a[1] = test_uniform(-40, 180);
            a[2] = test_uniform(-180, 140);
            b[0] = wrap180(a[0] + test_uniform(-len, len));
            b[1] = fmin(180, fmax(-40, a[1] + test_uniform(-len, len)));
            b[2] = fmin(140, fmax(-180, a[2] + test_uniform(-len, len)));
            if (qrt_motion_free_on_mask(&pl.mask, a, b)) {
                double c = motion_clearance(a, b, pts, n, radius);
                accepted_mask++;
                CHECK(c >= 0.0,
                      "mask walk accepted a colliding motion "
                      "(%g %g %g)->(%g %g %g): %g",
                      a[0], a[1], a[2], b[0], b[1], b[2], c);
            } else {
                /* where the walk fails, the configuration it names is
                 * called colliding exactly when the reference says so */
                double t, d[3], q[3];
                int j, hit;
                CHECK(!qrt_motion_free_on_mask_hit(&pl.mask, a, b, &t) &&
                          t >= 0.0 && t <= 1.0,
                      "walk hit at %g", t);
                hit = qrt_motion_collides_at(&prm.arm, pl.radius_m, &pl.points,
                                             &pl.mask.lat, a, b, t);
                d[0] = wrap180(b[0] - a[0]);
                d[1] = b[1] - a[1];
                d[2] = b[2] - a[2];
                for (j = 0; j < 3; j++)
                    q[j] = a[j] + t * d[j];
                CHECK(hit == (ref_clearance(q, pts, n, radius) <= 1e-7),
                      "collides_at %d, reference clearance %g", hit,
                      ref_clearance(q, pts, n, radius));
                collided_at += hit;
            }
            /* the witness search after 4 steps (joins) or first (paths);
             * block boxes change how fast, never the answer */
            if (i % 4 == 0) {
                int witness = i % 8 == 0 ? QRT_WITNESS_AFTER : 0;
                int plain = qrt_motion_free_exact(
                        &prm.arm, pl.radius_m, &pl.points, NULL, &pl.mask.lat,
                        a, b, 1000, witness),
                    boxed = qrt_motion_free_exact(
                        &prm.arm, pl.radius_m, &pl.points,
                        (const float(*)[6])boxes, &pl.mask.lat, a, b, 1000,
                        witness);
                CHECK(plain == boxed, "with block boxes %d, without %d", boxed,
                      plain);
                if (plain) {
                    double c = motion_clearance(a, b, pts, n, radius);
                    accepted_exact++;
                    CHECK(c >= 0.0,
                          "advancement accepted a colliding motion: %g", c);
                }
            }
        }
    }
    check_clearance();
    check_box_edges();
    printf("motions accepted: mask %d, exact %d\n", accepted_mask,
           accepted_exact);
    CHECK(accepted_mask > test_count(1000) && accepted_exact > test_count(200),
          "too few accepted");
    CHECK(collided_at >= test_count(20), "only %d walks failed in a collision",
          collided_at);
    {
        /* the seam: 175 -> -175 is a 10 degree move, not 350 */
        double a[3] = {175, 0, 0}, b[3] = {-175, 0, 0}, d[3];
        qrt_motion_delta(&pl.mask.lat, a, b, d);
        CHECK(fabs(d[0] - 10.0) < 1e-12, "seam step %g", d[0]);
    }
    return test_done("test_motion");
}
