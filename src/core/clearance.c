/* A path's certified clearance: conservative advancement that keeps the
 * least clearance between samples instead of stopping at a contact.
 *
 * Between two samples of a straight motion the clearance d(t) changes no
 * faster than the fastest point of the arm moves, so over a step in which
 * the arm moves at most m, with c0 and c1 the clearances at its ends,
 * d >= max(c0 - x, c1 - (m - x)) at a point x along it, and so
 * d >= min(c0, c1, (c0 + c1 - m) / 2) over the whole step. A step lets the
 * arm move (its clearance less the least clearance sampled so far) plus
 * QRT_CERTIFY_SLACK_M, so every step's bound is within half the slack of
 * the least sample, and steps are long where the arm is far from every
 * point. A sample more than QRT_CERTIFY_CAP_ABOVE_M above the least so far
 * stops measuring there: the capped value is still a lower bound. */
#include "clearance.h"

#include <math.h>

#include "motion.h"
#include "qrtplan/planner.h"
#include "tuning.h"

/* The clearance of the arm's own capsules at q (at most cap): from the
 * table's points, and from the points ignored as out of reach, which lie
 * at least their least distance from the base less how far out the arm
 * reaches at q away (like the distance to a point, that changes no faster
 * than the arm moves). */
static double sample(const struct qrt_arm *arm, const struct qrt_points *pts,
                     const float (*block_box)[6], const double q[3], double cap)
{
    double p[QRT_CHAIN_MAX + 1][3], radius[QRT_CHAIN_MAX], c = cap;
    int k, n = qrt_arm_capsules(arm, q, 0.0, p, radius);
    if (pts->far_min2 < QRT_NO_FAR_POINT) {
        double far = sqrt(pts->far_min2), widest = 0.0;
        for (k = 0; k < n; k++)
            if (radius[k] > widest)
                widest = radius[k];
        for (k = 1; k <= n; k++) { /* a capsule's farthest point: an end's */
            double e =
                sqrt(p[k][0] * p[k][0] + p[k][1] * p[k][1] + p[k][2] * p[k][2]);
            if (far - e - widest < c)
                c = far - e - widest;
        }
    }
    if (pts->count == 0)
        return c;
    return qrt_chain_clearance_capped((const double(*)[3])p, radius, n, pts,
                                      block_box, c);
}

static double min2(double a, double b)
{
    return a < b ? a : b;
}

double qrt_path_clearance(const struct qrt_arm *arm,
                          const struct qrt_arm *collision_arm,
                          const struct qrt_points *pts,
                          const struct qrt_lattice *lat, float (*block_box)[6],
                          const double (*wp_deg)[3], int n)
{
    double least, lower, c;
    int i;
    if ((pts->count == 0 && pts->far_min2 >= QRT_NO_FAR_POINT) || n < 1)
        return QRT_CLEARANCE_NONE_M;
    qrt_points_block_boxes(pts, block_box);
    c = sample(arm, pts, (const float(*)[6])block_box, wp_deg[0],
               QRT_CLEARANCE_NONE_M);
    least = lower = c;
    for (i = 1; i < n; i++) {
        double d[3], speed[3], t = 0.0;
        long step, steps;
        int j;
        qrt_motion_delta(lat, wp_deg[i - 1], wp_deg[i], d);
        qrt_motion_link_speeds(collision_arm, d, speed);
        /* the last link's speed bounds every point of the arm: it reaches
         * farthest from every joint's axis; every step but the last lets
         * the arm move at least the slack, which bounds their count */
        steps = (long)(speed[2] / QRT_CERTIFY_SLACK_M) + 2L;
        for (step = 0; step < steps; step++) {
            double q[3], c1, move, t1 = 1.0;
            if (!(t < 1.0))
                break;
            if (c - least + QRT_CERTIFY_SLACK_M < speed[2] * (1.0 - t))
                t1 = t + (c - least + QRT_CERTIFY_SLACK_M) / speed[2];
            for (j = 0; j < 3; j++)
                q[j] = wp_deg[i - 1][j] + t1 * d[j];
            c1 = sample(arm, pts, (const float(*)[6])block_box, q,
                        least + QRT_CERTIFY_CAP_ABOVE_M);
            move = speed[2] * (t1 - t);
            lower = min2(lower, min2(min2(c, c1), 0.5 * (c + c1 - move)));
            least = min2(least, c1);
            c = c1;
            t = t1;
        }
        if (t < 1.0) /* never (see steps); were it, the rest's own bound */
            lower = min2(lower, c - speed[2] * (1.0 - t));
    }
    return lower - qrt_points_inflation_m(pts);
}
