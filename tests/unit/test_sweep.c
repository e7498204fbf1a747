/* The one-pass proof of a straight motion against the points: every motion
 * it accepts is free when sampled every 0.1 degrees with the reference arm,
 * on clouds with points put next to the motion's own sampled
 * configurations (just inside and just outside a link's radius) and with
 * patches of 8 points, one of them near a link, round, in two halves of
 * different reach, or with one point nearer than the rest at each place
 * (the runs the proof takes by one ball, then by halves), across
 * the alpha seam, with alpha still, turning over pi (an alpha that does not
 * wrap), and for no motion at all; and it does
 * prove motions that pass the points with room to spare. A point a hair
 * (1e-9 to 1e-7 m) inside a link at the start stops the proof, however
 * the float test of points off the sweep rounds. In a table of points all
 * near the sweep and clear of it, one moved onto the arm stops the proof
 * at every place in the table. Uses the core's internal sweep.h. */
#include "../../src/core/geom.h"
#include "../../src/core/sweep.h"
#include "check.h"
#include "qrtplan/qrtplan.h"
#include "ref_arm.h"
#include "stored_points.h"

static struct qrt_planner pl;

/* A motion's own points; before them up to PAD_BEFORE points (a multiple
 * of 16, so that the patches keep their places among the samples), after
 * them up to PAD_AFTER, all out of the arm's reach: the test's points fall
 * anywhere in the blocks and spans the proof scans the table by. */
enum {
    CLOUD = 30,
    PAD_BEFORE = 128,
    PAD_AFTER = 47,
    HAIR_CLOUD = 16 + 2 * 64 + 47
};

static double wrap180(double x)
{
    x = fmod(x, 360.0);
    return x <= -180.0 ? x + 360.0 : (x > 180.0 ? x - 360.0 : x);
}

/* Alpha's change from a to b: the short way when alpha wraps. */
static double alpha_turn(const double a[3], const double b[3], int wraps)
{
    return wraps ? wrap180(b[0] - a[0]) : b[0] - a[0];
}

/* Samples of the motion a -> b every 0.1 degrees of its largest joint
 * change, and the configuration at sample k of them. */
static int samples_of(const double a[3], const double b[3], int wraps)
{
    double span = fmax(fabs(alpha_turn(a, b, wraps)),
                       fmax(fabs(b[1] - a[1]), fabs(b[2] - a[2])));
    return (int)ceil(span / 0.1) + 1;
}

static void config_at(const double a[3], const double b[3], int wraps, int k,
                      int steps, double q[3])
{
    q[0] = a[0] + alpha_turn(a, b, wraps) * k / steps;
    q[1] = a[1] + (b[1] - a[1]) * k / steps;
    q[2] = a[2] + (b[2] - a[2]) * k / steps;
}

/* A random spot on link k at configuration q, and a random unit direction
 * from it away from the link's axis. */
static void ray_from_link(const double q[3], int k, double spot[3],
                          double dir[3])
{
    double p[4][3], axis[3], s = test_uniform(0.0, 1.0), len, dot;
    int j;
    ref_fk(q, p);
    for (j = 0; j < 3; j++) {
        axis[j] = p[k + 1][j] - p[k][j];
        spot[j] = p[k][j] + s * axis[j];
        dir[j] = test_uniform(-1.0, 1.0);
    }
    len = sqrt(axis[0] * axis[0] + axis[1] * axis[1] + axis[2] * axis[2]);
    dot =
        (dir[0] * axis[0] + dir[1] * axis[1] + dir[2] * axis[2]) / (len * len);
    for (j = 0; j < 3; j++) /* across the link: off the axis' direction */
        dir[j] -= dot * axis[j];
    len = sqrt(dir[0] * dir[0] + dir[1] * dir[1] + dir[2] * dir[2]);
    for (j = 0; j < 3; j++)
        dir[j] /= len;
}

/* A point `offset` beyond link k's radius from a random spot on link k at
 * configuration q, in a random direction away from the link's axis. */
static void point_near(const double q[3], int k, double radius, double offset,
                       double x[3])
{
    double spot[3], dir[3];
    int j;
    ray_from_link(q, k, spot, dir);
    for (j = 0; j < 3; j++)
        x[j] = spot[j] + dir[j] * (radius + offset);
}

/* x within `spread` (a ball) of c. */
static void jitter(const double c[3], double spread, double x[3])
{
    double d[3];
    int k;
    do {
        for (k = 0; k < 3; k++)
            d[k] = test_uniform(-spread, spread);
    } while (d[0] * d[0] + d[1] * d[1] + d[2] * d[2] > spread * spread);
    for (k = 0; k < 3; k++)
        x[k] = c[k] + d[k];
}

static void random_joints(double q[3])
{
    q[0] = test_uniform(-180, 180);
    q[1] = test_uniform(-40, 180);
    q[2] = test_uniform(-180, 140);
}

/* A point a hair inside the widest link's radius at the motion's start
 * (the outermost such link: float's rounding grows with |x|), straight
 * across the arm's plane from the link's axis. Its w there is the wall
 * less 1e-9 to 1e-7 m, so only a margin for rounding keeps the float test
 * of whether a point is off the sweep from putting it off. The motion
 * turns alpha either way, so that at its end the point is far from the
 * plane, or on it. The point is the table's 1st to 16th in turn, since
 * every 16th is tried apart. Returns how many such points were inside the
 * radius as stored, each of which must have stopped the proof. */
static int hair_inside(const struct qrt_params *prm,
                       const struct qrt_lattice *lat, const double radius[3])
{
    static double cloud[3 * HAIR_CLOUD], stored[3 * HAIR_CLOUD];
    double a[3], b[3], p[4][3], n[2], side, depth, s;
    int trial, i, k, widest = 0, inside = 0, count;
    for (k = 1; k < 3; k++)
        if (radius[k] >= radius[widest])
            widest = k;
    for (trial = 0; trial < test_count(2000); trial++) {
        random_joints(a);
        for (k = 0; k < 3; k++)
            b[k] = a[k];
        b[0] = wrap180(a[0] + test_uniform(-60.0, 60.0));
        ref_fk(a, p);
        n[0] = -sin(a[0] * QRT_DEG);
        n[1] = cos(a[0] * QRT_DEG);
        side = trial % 2 ? 1.0 : -1.0;
        depth = pow(10.0, test_uniform(-9.0, -7.0));
        s = test_uniform(0.2, 0.8);
        /* 16 to HAIR_CLOUD points: the hair's place in the table anywhere
         * (a sample, in a block of the off-sweep test, or after them) */
        count = 16 + trial % (HAIR_CLOUD - 15);
        for (i = 0; i < count; i++) { /* the others 1 m below the base */
            cloud[3 * i] = 0.0;
            cloud[3 * i + 1] = 0.0;
            cloud[3 * i + 2] = -1.0 - 0.01 * i;
        }
        i = (int)test_uniform(0.0, count - 0.5);
        for (k = 0; k < 3; k++)
            cloud[3 * i + k] =
                p[widest][k] + s * (p[widest + 1][k] - p[widest][k]);
        cloud[3 * i] += side * (radius[widest] - depth) * n[0];
        cloud[3 * i + 1] += side * (radius[widest] - depth) * n[1];
        qrt_points_reset(&pl.points, 10.0);
        CHECK(qrt_points_add(&pl.points, cloud, count) == QRT_OK, "add");
        stored_points(&pl.points, count, stored);
        if (ref_clearance(a, stored, count, radius) >= -1e-9)
            continue; /* rounded to float, it came out */
        inside++;
        CHECK(!qrt_sweep_free(&prm->arm, radius, &pl.points, lat, a, b,
                              pl.search.sweep),
              "proved free, yet point %d is %.2g m inside link %d at the "
              "start: (%.2f %.2f %.2f), alpha to %.2f",
              i, depth, widest, a[0], a[1], a[2], b[0]);
    }
    return inside;
}

/* A table whose every point is near the sweep (in the arm's plane, which
 * stays put, but out of its reach), then either nothing or OFF_TAIL points
 * off it (across the plane), so that the last sample is near it or off it:
 * the proof passes it; and with any one near entry moved onto link 2 at the
 * start, wherever it lies in the runs the proof gathers and moves on between
 * spans, or among the samples' runs, the proof fails. Returns how many
 * places were tried. */
static int every_place(const struct qrt_params *prm,
                       const struct qrt_lattice *lat, const double radius[3])
{
    enum { ALL_NEAR = 21 * 16 + 5, OFF_TAIL = 20 };
    static double cloud[3 * (ALL_NEAR + OFF_TAIL)];
    double a[3], b[3], p[4][3];
    int trial, i, k, tail, places = 0;
    for (trial = 0; trial < test_count(4); trial++) {
        random_joints(a);
        b[0] = a[0]; /* alpha still: the plane stays put */
        b[1] = fmin(180, fmax(-40, a[1] + test_uniform(-20, 20)));
        b[2] = fmin(140, fmax(-180, a[2] + test_uniform(-20, 20)));
        for (i = 0; i < ALL_NEAR; i++) { /* 1.2 to 2 m out, in the plane */
            double u = (i % 2 ? 1.0 : -1.0) * test_uniform(1.2, 2.0);
            cloud[3 * i] = u * cos(a[0] * QRT_DEG);
            cloud[3 * i + 1] = u * sin(a[0] * QRT_DEG);
            cloud[3 * i + 2] = test_uniform(-1.0, 1.0);
        }
        for (; i < ALL_NEAR + OFF_TAIL; i++) { /* 1.5 m across the plane */
            cloud[3 * i] = -1.5 * sin(a[0] * QRT_DEG);
            cloud[3 * i + 1] = 1.5 * cos(a[0] * QRT_DEG);
            cloud[3 * i + 2] = test_uniform(-1.0, 1.0);
        }
        ref_fk(a, p);
        for (tail = 0; tail <= OFF_TAIL; tail += OFF_TAIL) {
            int count = ALL_NEAR + tail;
            qrt_points_reset(&pl.points, 10.0);
            CHECK(qrt_points_add(&pl.points, cloud, count) == QRT_OK, "add");
            CHECK(qrt_sweep_free(&prm->arm, radius, &pl.points, lat, a, b,
                                 pl.search.sweep),
                  "trial %d: points all out of reach, yet not proved", trial);
            for (i = 0; i < ALL_NEAR; i++) {
                double keep[3];
                for (k = 0; k < 3; k++) {
                    keep[k] = cloud[3 * i + k];
                    cloud[3 * i + k] = 0.5 * (p[1][k] + p[2][k]);
                }
                qrt_points_reset(&pl.points, 10.0);
                CHECK(qrt_points_add(&pl.points, cloud, count) == QRT_OK,
                      "add");
                CHECK(!qrt_sweep_free(&prm->arm, radius, &pl.points, lat, a, b,
                                      pl.search.sweep),
                      "trial %d: entry %d of %d on link 2 at the start, yet "
                      "proved free",
                      trial, i, count);
                places++;
                for (k = 0; k < 3; k++)
                    cloud[3 * i + k] = keep[k];
            }
        }
    }
    return places;
}

int main(void)
{
    static double all[3 * (PAD_BEFORE + CLOUD + PAD_AFTER)],
        stored[3 * (PAD_BEFORE + CLOUD + PAD_AFTER)];
    struct qrt_params prm;
    struct qrt_arm short_alpha; /* alpha in [-180, 175]: it does not wrap */
    struct qrt_lattice lat_wraps, lat_no_wrap;
    double radius[3];
    int trial, k, proved_roomy = 0, roomy = 0, colliding = 0, proved = 0;
    int patches_colliding = 0, patches_proved = 0;
    test_seed(0x5eed5eedULL);
    qrt_params_default(&prm);
    for (k = 0; k < 3; k++)
        radius[k] = prm.arm.link_radius_m[k] + prm.margin_m;
    CHECK(qrt_planner_init(&pl, &prm) == QRT_OK, "init");
    short_alpha = prm.arm;
    short_alpha.limit_deg[0][1] = 175.0;
    CHECK(qrt_lattice_init(&lat_wraps, &prm.arm, 5.0) == QRT_OK &&
              lat_wraps.alpha_wraps,
          "a lattice whose alpha wraps");
    CHECK(qrt_lattice_init(&lat_no_wrap, &short_alpha, 5.0) == QRT_OK &&
              !lat_no_wrap.alpha_wraps,
          "a lattice whose alpha does not wrap");
    for (trial = 0; trial < test_count(1200); trial++) {
        /* kinds: 0 points anywhere in reach; 1 and 2 one point next to
         * the motion within 1 cm (2: 3 mm) either way of a link's radius
         * (so that the answer turns on it alone), the others next to it
         * with room; 3 all with room; 4 patches of 8 points (a scan's
         * surfaces, which the proof takes as runs by one ball each): the
         * first near a link (below), the others with room */
        int kind = trial % 5, i, steps, free_here, wraps = 1, before, after,
            count;
        double centre[3], spot[3], ray[3], ray_offset = 0.0, *cloud;
        double a[3], b[3], worst = 1e30;
        random_joints(a);
        random_joints(b);
        if (trial % 10 == 1) { /* across the seam */
            a[0] = test_uniform(150, 180);
            b[0] = test_uniform(-180, -150);
        } else if (trial % 10 == 2) { /* alpha still */
            b[0] = a[0];
        } else if (trial % 10 == 3) { /* a short motion */
            for (k = 0; k < 3; k++)
                b[k] = a[k] + test_uniform(-3, 3);
            b[0] = wrap180(b[0]);
            b[1] = fmin(180, fmax(-40, b[1]));
            b[2] = fmin(140, fmax(-180, b[2]));
        } else if (trial % 10 == 4) { /* none at all */
            for (k = 0; k < 3; k++)
                b[k] = a[k];
        } else if (trial % 10 == 5) { /* an arm whose alpha does not wrap
                                          turns the long way, over pi */
            wraps = 0;
            a[0] = test_uniform(-180, -120);
            b[0] = test_uniform(120, 175);
        }
        steps = samples_of(a, b, wraps);
        before = 16 * (int)test_uniform(0.0, PAD_BEFORE / 16 + 0.99);
        after = (int)test_uniform(0.0, PAD_AFTER + 0.99);
        count = before + CLOUD + after;
        cloud = all + 3 * before;
        for (i = 0; i < before + after; i++) {
            /* beyond the arm's reach (0.96 m and a radius): clear of every
             * motion, some off the sweep by its ends, some not */
            double *x = all + 3 * (i < before ? i : CLOUD + i), d = 0.0;
            for (k = 0; k < 3; k++) {
                x[k] = test_uniform(-1.0, 1.0);
                d += x[k] * x[k];
            }
            d = test_uniform(1.1, 2.0) / sqrt(d + 1e-12);
            for (k = 0; k < 3; k++)
                x[k] *= d;
        }
        for (i = 0; i < CLOUD; i++) {
            double *x = cloud + 3 * i;
            if (kind == 0) {
                do {
                    for (k = 0; k < 3; k++)
                        x[k] = test_uniform(-1.0, 1.0);
                } while (x[0] * x[0] + x[1] * x[1] + x[2] * x[2] > 1.0);
            } else if (kind == 4 && i > 0) {
                /* point 0 is alone; patches from 1 on, so that none holds
                 * a point the proof tries first alone (every 16th). The
                 * first is round; or two halves on one ray from the
                 * link, 5 to 7 cm out, then -1 to 2 cm (a run whose
                 * halves' balls differ); or 5 to 7 cm out but for one
                 * point at -1 to 2 cm, at each place of the patch in
                 * turn (so that a ball that left out the point at any
                 * place in its run of the table would be caught) */
                int patch = (i - 1) / 8, link = (patch + trial / 5) % 3,
                    split = (trial / 5) % 3, odd = 1 + (trial / 15) % 8;
                if ((i - 1) % 8 == 0) {
                    double q[3];
                    int at = (int)test_uniform(0, steps + 1);
                    config_at(a, b, wraps, at > steps ? steps : at, steps, q);
                    ray_from_link(q, link, spot, ray);
                    ray_offset = patch == 0 && !split ? test_uniform(0.0, 0.04)
                                 : patch == 0         ? test_uniform(0.05, 0.07)
                                                      : test_uniform(0.1, 0.3);
                }
                if (i == 5 && split == 1)
                    ray_offset = test_uniform(-0.01, 0.02);
                if (split == 2 && patch == 0 && (i == odd || i == odd + 1))
                    ray_offset = i == odd ? test_uniform(-0.01, 0.02)
                                          : test_uniform(0.05, 0.07);
                for (k = 0; k < 3; k++)
                    centre[k] = spot[k] + ray[k] * (radius[link] + ray_offset);
                jitter(centre, patch == 0 && split ? 0.005 : 0.03, x);
            } else {
                double q[3];
                int at = (int)test_uniform(0, steps + 1),
                    link = (i + trial / 4) % 3;
                if (at > steps)
                    at = steps;
                config_at(a, b, wraps, at, steps, q);
                point_near(q, link, radius[link],
                           kind == 1 && i == 0   ? test_uniform(-0.01, 0.01)
                           : kind == 2 && i == 0 ? test_uniform(-0.003, 0.003)
                                                 : test_uniform(0.03, 0.3),
                           x);
            }
        }
        qrt_points_reset(&pl.points, 10.0);
        CHECK(qrt_points_add(&pl.points, all, count) == QRT_OK, "add");
        /* the reference reads the points as stored (floats) */
        stored_points(&pl.points, count, stored);
        for (i = 0; i <= steps; i++) {
            double q[3];
            config_at(a, b, wraps, i, steps, q);
            worst = fmin(worst, ref_clearance(q, stored, count, radius));
        }
        free_here = qrt_sweep_free(&prm.arm, radius, &pl.points,
                                   wraps ? &lat_wraps : &lat_no_wrap, a, b,
                                   pl.search.sweep);
        proved += free_here;
        if (free_here)
            CHECK(worst >= -1e-9,
                  "proved free, yet clearance %.3g m on a sample: "
                  "(%.2f %.2f %.2f) -> (%.2f %.2f %.2f), kind %d",
                  worst, a[0], a[1], a[2], b[0], b[1], b[2], kind);
        if (worst < 0.0)
            colliding++;
        if (kind == 4) {
            patches_colliding += worst < 0.0;
            patches_proved += free_here;
        }
        if (worst >= 0.025) {
            roomy++;
            proved_roomy += free_here;
        }
    }
    CHECK(every_place(&prm, &lat_wraps, radius) > 0, "no place tried");
    k = hair_inside(&prm, &lat_wraps, radius);
    CHECK(k > test_count(2000) / 2, "only %d points a hair inside", k);
    /* the cases must all have occurred, or the checks above proved little */
    CHECK(colliding > test_count(1200) / 10, "%d colliding motions", colliding);
    CHECK(roomy > test_count(1200) / 10, "%d motions with room", roomy);
    CHECK(patches_colliding > test_count(1200) / 50 &&
              patches_proved > test_count(1200) / 50,
          "patches: %d colliding, %d proved", patches_colliding,
          patches_proved);
    CHECK(proved_roomy >= roomy * 9 / 10,
          "proved only %d of %d motions that pass every point by 2.5 cm",
          proved_roomy, roomy);
    printf("proved %d of %d motions; %d of the %d with 2.5 cm to spare; %d "
           "collide; patches: %d collide, %d proved\n",
           proved, (int)test_count(1200), proved_roomy, roomy, colliding,
           patches_colliding, patches_proved);
    return test_done("test_sweep");
}
