/* Proving a straight motion free against the points in one pass over them
 * (see sweep.h). */
#include "sweep.h"

#include <math.h>

#include "fastmath.h"
#include "geom.h"
#include "motion.h"
#include "tuning.h"

/* The tuning of this proof is in tuning.h (QRT_SWEEP_*): the stored poses
 * lie QRT_SWEEP_POSE_SPACING_M apart for the arm's fastest point, at most
 * QRTI_SWEEP_POSES of them (a point that clear of the arm is passed with
 * them alone, a closer one needs configurations computed for it); the
 * proof takes at most QRT_SWEEP_STEPS_PER_POINT steps for one point and
 * QRT_SWEEP_STEPS_MEAN a point (plus QRT_SWEEP_STEPS_START) over all, and
 * a motion that brushes past points is left to the mask, which decides it
 * for less.
 *
 * Every QRT_SWEEP_SAMPLE_STRIDE-th point is a sample and is tried first: a
 * motion is seldom blocked by one point alone, so a blocked one is usually
 * told from a sample. The samples near the sweep are tried
 * QRT_SWEEP_SAMPLE_RUN at a time, by one ball that holds them, then one by
 * one: such samples span a stretch of a scan that is often a patch small
 * enough for the ball to clear, and a run that fails costs one ball more.
 * The off-sweep test is made on blocks of QRT_SWEEP_OFF_BLOCK entries (a
 * multiple of the stride, so that a block's samples are its entries 0,
 * stride, ...).
 *
 * Points near the sweep, taken in the table's order, are tried first as
 * runs of QRT_SWEEP_RUN_POINTS by one ball that holds them all, then as
 * halves, each by its own ball, down to groups of QRT_SWEEP_RUN_GROUP
 * points: a scan's points lie in its order along surfaces, so such a run
 * is often a small patch that clears the arm as a whole. A ball wider than
 * QRT_SWEEP_RUN_BALL_M is not tried; a ball's proof takes at most
 * QRT_SWEEP_RUN_STEPS steps (a run that brushes past the arm is quicker
 * told point by point). */

/* Clearance at or under this (metres) counts as contact, as in motion.c. */
#define CONTACT_M 1e-7
#define OFF_SPANS (QRT_SWEEP_OFF_BLOCK / QRT_SWEEP_SAMPLE_STRIDE)
/* How many sizes of ball a run is tried with (from QRT_SWEEP_RUN_POINTS
 * halved down to QRT_SWEEP_RUN_GROUP), which bounds the spans waiting to
 * be tried (one more than the halvings). */
#define RUN_LEVELS 4
#if (QRT_SWEEP_RUN_POINTS >> (RUN_LEVELS - 1)) != QRT_SWEEP_RUN_GROUP
#error                                                                         \
    "RUN_LEVELS must count the halvings from QRT_SWEEP_RUN_POINTS to QRT_SWEEP_RUN_GROUP"
#endif

/* Is a point off the sweep, farther than W from the arm's plane all along
 * the motion, by the plane's two ends alone? |w| = rho |sin(phi - alpha)|
 * is concave in alpha between its zeros, which lie pi apart: on a turn
 * shorter than pi, the same sign of w at both ends means no zero between
 * them, and the least |w| at an end. So with a = w0 and b = w1 it is
 * min(a, b) > W or max(a, b) < -W; that is |a + b| - |a - b| > 2 W (for
 * W > 0 one of the two cannot hold, and min, max are (a + b -+ |a - b|) / 2),
 * and a + b, a - b are w along the sum and the difference of the ends'
 * normals: four products, and no branch for min and max. Most points leave
 * here, so it is done in float, and 2 W grows by more than that can be off:
 * rounded to float, the normals' sum and difference are off by 2^-23, the
 * products and sums by 2^-24 of 2 (|x| + |y|) each, the difference of the
 * magnitudes by 2^-24 of 4 (|x| + |y|). That is 2^-20 (|x| + |y|), under
 * 2^-19 reach for a point within `reach` of the base, so 2 W grows by
 * 2^-18 reach. A point farther out than `reach` (the arm's links and its
 * widest radius) cannot touch the arm, so what the test says of it is true
 * either way. */
struct float_ends {
    float sum_x, sum_y, diff_x, diff_y, wall2;
};

struct sweep {
    double link[3];
    double a0, da, s0, ds, p0, dp; /* alpha, sigma and sigma + eta, radians:
                                      at t = 0, and their change to t = 1 */
    double radius[3];
    /* how fast (metres per unit of t) any point of link k can move, each
     * joint's rate times the farthest the link reaches from its axis; and
     * its inverse (huge for a link that does not move) */
    double speed[3], inv_speed[3];
    double wall; /* a point farther than this from the arm's plane is clear
                    of every link */
    struct float_ends ends; /* for float_off */
    long n;                 /* stored configurations, at t = (i + 0.5) / n */
    struct qrti_sweep_pose *pose;
    long steps_left;
    int max_steps; /* for one point or ball */
    /* how often a ball of each size (level 0 the whole run) cleared */
    long balls_cleared[RUN_LEVELS], balls_failed[RUN_LEVELS];
};

static void pose_at(const struct sweep *s, double t, struct qrti_sweep_pose *lf)
{
    double a = s->a0 + t * s->da, sg = s->s0 + t * s->ds,
           ps = s->p0 + t * s->dp;
    lf->ca = cos(a);
    lf->sa = sin(a);
    lf->cs = cos(sg);
    lf->ss = sin(sg);
    lf->cp = cos(ps);
    lf->sp = sin(ps);
    lf->elbow_u = s->link[0] + s->link[1] * lf->cs;
    lf->elbow_z = s->link[1] * lf->ss;
}

/* c + i s turned by the angle whose cosine and sine are cd, sd. */
static void turn(double *c, double *sn, double cd, double sd)
{
    double c0 = *c;
    *c = c0 * cd - *sn * sd;
    *sn = *sn * cd + c0 * sd;
}

/* The stored configurations at t = (i + 1/2) / n: the first computed, each
 * next one turned from the one before by the same angles. The rounding
 * adds about 1e-16 rad a step, some 1e-13 m over 256 steps at the arm's
 * reach: the CONTACT_M kept off every clearance covers it many times. */
static void store_poses(const struct sweep *s, struct qrti_sweep_pose *pose)
{
    double inv_n = 1.0 / (double)s->n, ca = cos(s->da * inv_n),
           sa = sin(s->da * inv_n), cs = cos(s->ds * inv_n),
           ss = sin(s->ds * inv_n), cp = cos(s->dp * inv_n),
           sp = sin(s->dp * inv_n);
    long i;
    pose_at(s, 0.5 * inv_n, &pose[0]);
    for (i = 1; i < s->n; i++) {
        struct qrti_sweep_pose *lf = &pose[i];
        *lf = pose[i - 1];
        turn(&lf->ca, &lf->sa, ca, sa);
        turn(&lf->cs, &lf->ss, cs, ss);
        turn(&lf->cp, &lf->sp, cp, sp);
        lf->elbow_u = s->link[0] + s->link[1] * lf->cs;
        lf->elbow_z = s->link[1] * lf->ss;
    }
}

/* Squared distance, in the arm's plane, from (u, z) to the segment from
 * (u0, z0) along the unit direction (cu, cz) for len. */
static double seg_dist2(double u, double z, double u0, double z0, double cu,
                        double cz, double len)
{
    double du = u - u0, dz = z - z0, along = du * cu + dz * cz;
    if (along < 0.0)
        along = 0.0;
    else if (along > len)
        along = len;
    du -= along * cu;
    dz -= along * cz;
    return du * du + dz * dz;
}

/* For how long (in t, either way) from configuration lf every link stays
 * clear of p: the least over the links of clearance over speed. At or
 * under 0 where some link is in contact at lf itself. */
static double clear_time(const struct sweep *s,
                         const struct qrti_sweep_pose *lf, const double p[3])
{
    /* p in the arm's plane: u along the arm's bearing, w across it */
    double u = p[0] * lf->ca + p[1] * lf->sa, w = p[1] * lf->ca - p[0] * lf->sa,
           w2 = w * w, t, best;
    best = (sqrt(seg_dist2(u, p[2], 0.0, 0.0, 1.0, 0.0, s->link[0]) + w2) -
            s->radius[0] - CONTACT_M) *
           s->inv_speed[0];
    t = (sqrt(seg_dist2(u, p[2], s->link[0], 0.0, lf->cs, lf->ss, s->link[1]) +
              w2) -
         s->radius[1] - CONTACT_M) *
        s->inv_speed[1];
    if (t < best)
        best = t;
    t = (sqrt(seg_dist2(u, p[2], lf->elbow_u, lf->elbow_z, lf->cp, lf->sp,
                        s->link[2]) +
              w2) -
         s->radius[2] - CONTACT_M) *
        s->inv_speed[2];
    return t < best ? t : best;
}

/* Is p farther than reach[k] from link k at configuration lf, for every
 * link? (No roots: most points pass this once for their whole window.) */
static int clear_by(const struct sweep *s, const struct qrti_sweep_pose *lf,
                    const double p[3], const double reach[3])
{
    double u = p[0] * lf->ca + p[1] * lf->sa, w = p[1] * lf->ca - p[0] * lf->sa,
           w2 = w * w;
    return seg_dist2(u, p[2], 0.0, 0.0, 1.0, 0.0, s->link[0]) + w2 >
               reach[0] * reach[0] &&
           seg_dist2(u, p[2], s->link[0], 0.0, lf->cs, lf->ss, s->link[1]) +
                   w2 >
               reach[1] * reach[1] &&
           seg_dist2(u, p[2], lf->elbow_u, lf->elbow_z, lf->cp, lf->sp,
                     s->link[2]) +
                   w2 >
               reach[2] * reach[2];
}

/* Is p clear of the arm for every t in [tl, th]? First in one test from
 * the stored configuration nearest the middle, each link's radius grown by
 * how far it can move to either end; else by conservative advancement:
 * a configuration clear for dt covers t +- dt; the stored one nearest t
 * serves when it reaches back to t, else the configuration at t itself. */
static int advance(struct sweep *s, const double p[3], double tl, double th)
{
    double t = tl, reach[3], ti, far;
    long i = (long)(0.5 * (tl + th) * (double)s->n);
    int steps, k;
    if (i >= s->n)
        i = s->n - 1;
    ti = ((double)i + 0.5) / (double)s->n;
    far = ti - tl > th - ti ? ti - tl : th - ti;
    for (k = 0; k < 3; k++)
        reach[k] = s->radius[k] + CONTACT_M + s->speed[k] * far;
    if (clear_by(s, &s->pose[i], p, reach))
        return 1;
    for (steps = 0; steps < s->max_steps; steps++) {
        double dt;
        if (--s->steps_left < 0)
            return 0;
        i = (long)(t * (double)s->n);
        if (i >= s->n)
            i = s->n - 1;
        ti = ((double)i + 0.5) / (double)s->n;
        dt = clear_time(s, &s->pose[i], p);
        if (dt > fabs(t - ti)) {
            t = ti + dt;
        } else {
            struct qrti_sweep_pose here;
            pose_at(s, t, &here);
            dt = clear_time(s, &here, p);
            if (dt <= 0.0)
                return 0;
            t += dt;
        }
        if (t >= th)
            return 1;
    }
    return 0;
}

/* Is p clear of the arm along the whole motion? Only while alpha is near
 * p's bearing phi (or its opposite) can p be within `wall` of the arm's
 * plane: rho |sin(phi - alpha)| <= wall, that is phi - alpha within
 * beta = asin(wall / rho) <= (pi / 2) wall / rho of a multiple of pi. */
static int near_clear(struct sweep *s, const double p[3])
{
    double rho, beta, d0, lo, hi;
    long k, k_lo, k_hi;
    if (s->da == 0.0) { /* the plane stays put */
        double w = p[1] * s->pose[0].ca - p[0] * s->pose[0].sa;
        return fabs(w) > s->wall || advance(s, p, 0.0, 1.0);
    }
    rho = sqrt(p[0] * p[0] + p[1] * p[1]);
    beta = rho > 0.0 ? 0.5 * QRT_PI * s->wall / rho : QRT_PI;
    beta += QRT_FAST_ANGLE_ERR + 1e-9; /* the bearing's error, rounding */
    if (beta >= 0.5 * QRT_PI)          /* the windows would meet */
        return advance(s, p, 0.0, 1.0);
    d0 = qrt_fast_atan2(p[1], p[0]) - s->a0; /* in [-2 pi, 2 pi] */
    lo = s->da < 0.0 ? s->da : 0.0;          /* alpha - a0 on the motion */
    hi = s->da < 0.0 ? 0.0 : s->da;
    /* the windows d0 + k pi +- beta that meet [lo, hi] */
    k_lo = qrt_ceil((lo - beta - d0) / QRT_PI);
    k_hi = qrt_floor((hi + beta - d0) / QRT_PI);
    for (k = k_lo; k <= k_hi; k++) {
        double o = d0 + (double)k * QRT_PI, a = o - beta, b = o + beta, tl, th;
        if (a < lo)
            a = lo;
        if (b > hi)
            b = hi;
        if (a > b)
            continue;
        tl = a / s->da;
        th = b / s->da;
        if (tl > th) {
            double x = tl;
            tl = th;
            th = x;
        }
        tl = tl < 1e-12 ? 0.0 : tl - 1e-12;
        th = th > 1.0 - 1e-12 ? 1.0 : th + 1e-12;
        if (!advance(s, p, tl, th))
            return 0;
    }
    return 1;
}

/* near_clear for the table's entry i */
static int stored_near_clear(struct sweep *s, const struct qrt_point_axes *ax,
                             long i)
{
    double p[3];
    qrt_point_at(ax, i, p);
    return near_clear(s, p);
}

/* float_off's figures for a motion that turns alpha from a0 by da, of an
 * arm with these links whose widest radius is radius_wall. The plane's
 * normal at both ends is (-sin, cos) of alpha. W is the widest radius,
 * with 1e-9 m for the normals' rounding in double, where alpha turns by
 * less than pi; else infinite, and no point is put off. The 1e-6 covers
 * W's own rounding to float. */
static void float_ends_of(const double link[3], double radius_wall, double a0,
                          double da, struct float_ends *f)
{
    double reach = link[0] + link[1] + link[2] + radius_wall, n0x = -sin(a0),
           n0y = cos(a0), n1x = -sin(a0 + da), n1y = cos(a0 + da),
           wall = fabs(da) < QRT_PI - 1e-6 ? radius_wall + 1e-9 : HUGE_VAL;
    f->sum_x = (float)(n0x + n1x);
    f->sum_y = (float)(n0y + n1y);
    f->diff_x = (float)(n0x - n1x);
    f->diff_y = (float)(n0y - n1y);
    f->wall2 = (float)((2.0 * wall + 3.814697265625e-6 * reach) * (1.0 + 1e-6));
}

static int float_off(float x, float y, const struct float_ends *f)
{
    float along_sum = x * f->sum_x + y * f->sum_y,
          along_diff = x * f->diff_x + y * f->diff_y;
    return fabsf(along_sum) - fabsf(along_diff) > f->wall2;
}

/* Of the QRT_SWEEP_OFF_BLOCK entries from `at` on, mark in near[] those
 * float_off does not put off the sweep, and count them in each span of
 * QRT_SWEEP_SAMPLE_STRIDE entries, leaving out the span's first (its sample,
 * tried before, with the other samples). Loops of fixed count with no branch
 * over two axes: the compiler makes them 4 lanes wide. */
static void mark_near(const struct qrt_point_axes *ax, long at,
                      const struct float_ends *f, int near[QRT_SWEEP_OFF_BLOCK],
                      int count[OFF_SPANS])
{
    int b, j;
    for (b = 0; b < OFF_SPANS; b++) {
        const float *x = ax->x + at + b * QRT_SWEEP_SAMPLE_STRIDE,
                    *y = ax->y + at + b * QRT_SWEEP_SAMPLE_STRIDE;
        int *mark = near + b * QRT_SWEEP_SAMPLE_STRIDE, c = 0;
        for (j = 0; j < QRT_SWEEP_SAMPLE_STRIDE; j++) {
            mark[j] = float_off(x[j], y[j], f) ? 0 : 1;
            c += mark[j];
        }
        count[b] = c - mark[0];
    }
}

struct box {
    float lo[3], hi[3];
};

/* The box of the table's entries run[0..n-1], n >= 1. (Kept in locals
 * until the end: b's floats could alias the table's, so stores into b
 * would make every point be loaded again.) */
static void box_of(const struct qrt_point_axes *ax, const long *run, int n,
                   struct box *b)
{
    float lo_x = ax->x[run[0]], lo_y = ax->y[run[0]], lo_z = ax->z[run[0]],
          hi_x = lo_x, hi_y = lo_y, hi_z = lo_z;
    int i;
    for (i = 1; i < n; i++) {
        float x = ax->x[run[i]], y = ax->y[run[i]], z = ax->z[run[i]];
        lo_x = x < lo_x ? x : lo_x;
        hi_x = x > hi_x ? x : hi_x;
        lo_y = y < lo_y ? y : lo_y;
        hi_y = y > hi_y ? y : hi_y;
        lo_z = z < lo_z ? z : lo_z;
        hi_z = z > hi_z ? z : hi_z;
    }
    b->lo[0] = lo_x;
    b->lo[1] = lo_y;
    b->lo[2] = lo_z;
    b->hi[0] = hi_x;
    b->hi[1] = hi_y;
    b->hi[2] = hi_z;
}

/* Are the points in box b clear of the arm all along the motion, as one
 * ball about its centre? No when the ball is wider than QRT_SWEEP_RUN_BALL_M. A
 * point within r of the centre c comes no closer to a link than c comes less r,
 * so c kept farther than radius + r from every link keeps every member
 * farther than radius. */
static int ball_clear(const struct sweep *s, struct sweep *ball,
                      const struct box *b, int level)
{
    double c[3], r2 = 0.0, r;
    int k;
    /* c and r round off by under 2^-52 |c|: the 1e-12 m added covers that
     * within 1 km of the base, and no link comes near a ball farther out */
    for (k = 0; k < 3; k++) {
        double half = 0.5 * ((double)b->hi[k] - (double)b->lo[k]);
        c[k] = 0.5 * ((double)b->lo[k] + (double)b->hi[k]);
        r2 += half * half;
    }
    r = sqrt(r2) * (1.0 + 1e-12) + 1e-12;
    if (r <= QRT_SWEEP_RUN_BALL_M) {
        for (k = 0; k < 3; k++)
            ball->radius[k] = s->radius[k] + r;
        ball->wall = s->wall + r;
        if (near_clear(ball, c)) {
            ball->balls_cleared[level]++;
            return 1;
        }
    }
    ball->balls_failed[level]++;
    return 0;
}

static void box_merge(struct box *into, const struct box *b)
{
    int k;
    for (k = 0; k < 3; k++) {
        into->lo[k] = b->lo[k] < into->lo[k] ? b->lo[k] : into->lo[k];
        into->hi[k] = b->hi[k] > into->hi[k] ? b->hi[k] : into->hi[k];
    }
}

/* The table's entries run[0..n-1], none off the sweep by its ends: as one ball,
 * else as two halves, each as a ball, and so on down to QRT_SWEEP_RUN_GROUP
 * points (balls of at most `levels` sizes), else one by one; depth first, from
 * a small stack of spans (no recursion). Every span starts on a group's first
 * point and ends at a group's end or at n, so its groups' boxes merged are
 * exactly its box. Balls of a size are tried while they clear at least a third
 * of the time (and on every 16th run, so that a scene whose first runs were
 * wide can come back to them): in a table with no order in space, or where the
 * motion brushes past the points, their boxes are only cost. */
static int run_clear(struct sweep *s, struct sweep *ball,
                     const struct qrt_point_axes *ax, const long *run, int n,
                     long runs, int levels)
{
    struct box group[QRT_SWEEP_RUN_POINTS / QRT_SWEEP_RUN_GROUP], b;
    int first_of[RUN_LEVELS], count_of[RUN_LEVELS], level_of[RUN_LEVELS];
    int groups = (n + QRT_SWEEP_RUN_GROUP - 1) / QRT_SWEEP_RUN_GROUP, top = 1,
        i;
    for (i = 0; i < groups; i++) {
        int first = i * QRT_SWEEP_RUN_GROUP;
        box_of(ax, run + first,
               n - first < QRT_SWEEP_RUN_GROUP ? n - first
                                               : QRT_SWEEP_RUN_GROUP,
               &group[i]);
    }
    first_of[0] = 0;
    count_of[0] = n;
    level_of[0] = 0;
    while (top > 0) {
        int first, m, level, half;
        top--;
        first = first_of[top];
        m = count_of[top];
        level = level_of[top];
        if (m > 1 &&
            (ball->balls_failed[level] <= 2 * ball->balls_cleared[level] + 16 ||
             runs % 16 == 0)) {
            b = group[first / QRT_SWEEP_RUN_GROUP];
            for (i = first / QRT_SWEEP_RUN_GROUP + 1;
                 i <
                 (first + m + QRT_SWEEP_RUN_GROUP - 1) / QRT_SWEEP_RUN_GROUP;
                 i++)
                box_merge(&b, &group[i]);
            if (ball_clear(s, ball, &b, level))
                continue;
        }
        /* (the level's test is never needed: halving 32 points three
         * times leaves at most 4; it keeps the stack's bound plain) */
        if (m <= QRT_SWEEP_RUN_GROUP || level + 1 >= levels) {
            for (i = first; i < first + m; i++)
                if (!stored_near_clear(s, ax, run[i]))
                    return 0;
            continue;
        }
        /* the halves, split on a group's edge; the first is taken first */
        half = (m / QRT_SWEEP_RUN_GROUP + 1) / 2 * QRT_SWEEP_RUN_GROUP;
        first_of[top] = first + half;
        count_of[top] = m - half;
        level_of[top++] = level + 1;
        first_of[top] = first;
        count_of[top] = half;
        level_of[top++] = level + 1;
    }
    return 1;
}

int qrt_sweep_free(const struct qrt_arm *arm, const double radius_m[3],
                   const struct qrt_points *pts, const struct qrt_lattice *lat,
                   const double a_deg[3], const double b_deg[3],
                   struct qrti_sweep_pose *poses)
{
    struct sweep s, ball, sample_ball;
    struct float_ends ends;
    struct qrt_point_axes ax = qrt_points_axes(pts);
    double d[3], fastest;
    /* a span adds at most QRT_SWEEP_SAMPLE_STRIDE - 1 to fewer than
     * QRT_SWEEP_RUN_POINTS */
    long i, run[QRT_SWEEP_RUN_POINTS + QRT_SWEEP_SAMPLE_STRIDE], runs = 0;
    int k, n = 0;
    qrt_motion_delta(lat, a_deg, b_deg, d);
    qrt_motion_link_speeds(arm, d, s.speed);
    for (k = 0; k < 3; k++) {
        s.link[k] = arm->link_m[k];
        s.radius[k] = radius_m[k];
    }
    s.a0 = a_deg[0] * QRT_DEG;
    s.da = d[0] * QRT_DEG;
    s.s0 = a_deg[1] * QRT_DEG;
    s.ds = d[1] * QRT_DEG;
    s.p0 = (a_deg[1] + a_deg[2]) * QRT_DEG;
    s.dp = (d[1] + d[2]) * QRT_DEG;
    fastest = 0.0;
    s.wall = 0.0;
    for (k = 0; k < 3; k++) {
        s.inv_speed[k] = s.speed[k] > 0.0 ? 1.0 / s.speed[k] : 1e30;
        if (s.speed[k] > fastest)
            fastest = s.speed[k];
        if (radius_m[k] > s.wall)
            s.wall = radius_m[k];
    }
    float_ends_of(s.link, s.wall, s.a0, s.da, &s.ends);
    s.n = 1;
    while (s.n < QRTI_SWEEP_POSES &&
           (double)s.n * QRT_SWEEP_POSE_SPACING_M < fastest)
        s.n *= 2;
    s.pose = poses;
    s.steps_left = QRT_SWEEP_STEPS_MEAN * pts->count + QRT_SWEEP_STEPS_START;
    s.max_steps = QRT_SWEEP_STEPS_PER_POINT;
    for (k = 0; k < RUN_LEVELS; k++)
        s.balls_cleared[k] = s.balls_failed[k] = 0;
    store_poses(&s, poses);
    for (k = 0; k < QRT_SWEEP_RUN_POINTS + QRT_SWEEP_SAMPLE_STRIDE; k++)
        run[k] = 0; /* (the rest of a run is moved as a fixed count) */
    /* the balls' steps are counted apart: they only save work; the
     * samples' balls keep their own counts of how often they clear */
    ball = s;
    ball.max_steps = QRT_SWEEP_RUN_STEPS;
    ball.steps_left = QRT_SWEEP_STEPS_MEAN * pts->count + QRT_SWEEP_STEPS_START;
    sample_ball = ball;
    /* what the off-sweep test reads, in a local (run_clear is passed &s,
     * so s's fields would be loaded again for every point) */
    ends = s.ends;
    for (i = 0; i < pts->count; i += QRT_SWEEP_SAMPLE_STRIDE) {
        if (float_off(ax.x[i], ax.y[i], &ends))
            continue;
        run[n++] = i;
        if (n == QRT_SWEEP_SAMPLE_RUN) {
            if (!run_clear(&s, &sample_ball, &ax, run, n, runs++, 1))
                return 0;
            n = 0;
        }
    }
    if (n > 0 && !run_clear(&s, &sample_ball, &ax, run, n, runs, 1))
        return 0;
    n = 0;
    runs = 0;
    /* every point but the samples: in blocks marked by mark_near, then the
     * last entries one by one */
    for (i = 0; i + QRT_SWEEP_OFF_BLOCK <= pts->count;
         i += QRT_SWEEP_OFF_BLOCK) {
        int near[QRT_SWEEP_OFF_BLOCK], count[OFF_SPANS], b, j;
        mark_near(&ax, i, &ends, near, count);
        for (b = 0; b < OFF_SPANS; b++) {
            const int *mark = near + b * QRT_SWEEP_SAMPLE_STRIDE;
            long first = i + b * QRT_SWEEP_SAMPLE_STRIDE;
            if (count[b] == 0)
                continue;
            /* with no branch: every entry is written, the near ones kept */
            for (j = 1; j < QRT_SWEEP_SAMPLE_STRIDE; j++) {
                run[n] = first + j;
                n += mark[j];
            }
            if (n >= QRT_SWEEP_RUN_POINTS) { /* a run of QRT_SWEEP_RUN_POINTS;
                                                the rest kept */
                if (!run_clear(&s, &ball, &ax, run, QRT_SWEEP_RUN_POINTS,
                               runs++, RUN_LEVELS))
                    return 0;
                n -= QRT_SWEEP_RUN_POINTS;
                /* the rest, at most QRT_SWEEP_SAMPLE_STRIDE - 2 (n was under
                 * QRT_SWEEP_RUN_POINTS before the span), moved as a fixed
                 * count: no call to memmove */
                for (j = 0; j < QRT_SWEEP_SAMPLE_STRIDE - 2; j++)
                    run[j] = run[QRT_SWEEP_RUN_POINTS + j];
            }
        }
    }
    for (; i < pts->count; i++) {
        if (i % QRT_SWEEP_SAMPLE_STRIDE == 0 ||
            float_off(ax.x[i], ax.y[i], &ends))
            continue;
        run[n++] = i;
        if (n == QRT_SWEEP_RUN_POINTS) {
            if (!run_clear(&s, &ball, &ax, run, n, runs++, RUN_LEVELS))
                return 0;
            n = 0;
        }
    }
    return n == 0 || run_clear(&s, &ball, &ax, run, n, runs, RUN_LEVELS);
}
