/* Certifying straight joint-space motions against the mask or the points. */
#include "motion.h"

#include <math.h>
#include <stddef.h>

#include "bits.h"
#include "geom.h"

void qrt_motion_delta(const struct qrt_lattice *lat, const double a_deg[3],
                      const double b_deg[3], double d_deg[3])
{
    int j;
    for (j = 0; j < 3; j++)
        d_deg[j] = b_deg[j] - a_deg[j];
    if (lat->alpha_wraps)
        d_deg[0] = qrt_wrap_deg(d_deg[0]);
}

void qrt_motion_link_speeds(const struct qrt_arm *arm, const double d_deg[3],
                            double speed[3])
{
    const double *l = arm->link_m;
    double a = fabs(d_deg[0]), s = fabs(d_deg[1]), e = fabs(d_deg[2]);
    speed[0] = a * l[0] * QRT_DEG;
    speed[1] = (a * (l[0] + l[1]) + s * l[1]) * QRT_DEG;
    speed[2] =
        (a * (l[0] + l[1] + l[2]) + s * (l[1] + l[2]) + e * l[2]) * QRT_DEG;
}

/* The lattice node whose cell holds continuous lattice coordinates x;
 * 0 if that is outside the lattice. */
static int cell_of(const struct qrt_lattice *lat, const double x[3], int ijk[3])
{
    int j;
    for (j = 0; j < 3; j++) {
        double k = floor(x[j] + 0.5);
        if (j == 0 && lat->alpha_wraps)
            k -= lat->n[0] * floor(k / lat->n[0]);
        if (k < 0.0 || k > (double)(lat->n[j] - 1))
            return 0;
        ijk[j] = (int)k;
    }
    return 1;
}

/* Walk the motion a -> b cell by cell. Without rows: 1 if every cell is
 * free (outside the lattice counts as blocked). With rows: mark in it the
 * mask row (alpha, sigma) of every cell the walk would test, and return 1.
 * One walk for both, so a check on rows built from the marks looks at
 * exactly the rows that were built. */
static int walk(const struct qrt_mask *mask, qrt_node_blocked blocked,
                void *ctx, const double a_deg[3], const double b_deg[3],
                uint64_t *rows, double *t_hit)
{
    const struct qrt_lattice *lat = &mask->lat;
    double x0[3], dx[3], d[3], next_t[3], step_t[3], t = 0.0;
    int j;

    qrt_motion_delta(lat, a_deg, b_deg, d);
    /* Walk the parameter t in [0, 1] from one cell boundary (node +- half a
     * grid step on some axis) to the next; between two boundaries the
     * motion stays in one cell, named by its midpoint. */
    for (j = 0; j < 3; j++) {
        x0[j] = (a_deg[j] - lat->lo_deg[j]) / lat->grid_deg;
        dx[j] = d[j] / lat->grid_deg;
        if (dx[j] == 0.0) {
            next_t[j] = 2.0;
            step_t[j] = 0.0;
            continue;
        }
        step_t[j] = 1.0 / fabs(dx[j]);
        {
            double first = dx[j] > 0.0 ? floor(x0[j] + 0.5) + 0.5
                                       : ceil(x0[j] - 0.5) - 0.5;
            next_t[j] = (first - x0[j]) / dx[j];
        }
    }
    for (;;) {
        double t_end = 1.0, mid[3];
        int axis = -1, ijk[3], inside;
        for (j = 0; j < 3; j++)
            if (next_t[j] < t_end) {
                t_end = next_t[j];
                axis = j;
            }
        for (j = 0; j < 3; j++)
            mid[j] = x0[j] + 0.5 * (t + t_end) * dx[j];
        inside = cell_of(lat, mid, ijk);
        if (rows) {
            if (inside) {
                long bit = (long)ijk[0] * QRT_MAX_NS + ijk[1];
                qrt_bit_set(rows, bit);
            }
        } else {
            if (t_hit) /* where the motion is in the cell it fails in */
                *t_hit = 0.5 * (t + t_end);
            if (!inside)
                return 0;
            if (blocked ? blocked(ctx, ijk) : qrt_mask_blocked(mask, ijk))
                return 0;
        }
        if (axis < 0)
            return 1;
        t = t_end;
        next_t[axis] += step_t[axis];
    }
}

int qrt_motion_free_on_mask(const struct qrt_mask *mask, const double a_deg[3],
                            const double b_deg[3])
{
    return walk(mask, NULL, NULL, a_deg, b_deg, NULL, NULL);
}

int qrt_motion_free_asking(const struct qrt_mask *mask,
                           qrt_node_blocked blocked, void *ctx,
                           const double a_deg[3], const double b_deg[3])
{
    return walk(mask, blocked, ctx, a_deg, b_deg, NULL, NULL);
}

int qrt_motion_free_on_mask_hit(const struct qrt_mask *mask,
                                const double a_deg[3], const double b_deg[3],
                                double *t_hit)
{
    *t_hit = 0.0;
    return walk(mask, NULL, NULL, a_deg, b_deg, NULL, t_hit);
}

void qrt_motion_mark_rows(const struct qrt_mask *mask, const double a_deg[3],
                          const double b_deg[3], uint64_t *rows)
{
    (void)walk(mask, NULL, NULL, a_deg, b_deg, rows, NULL);
}

/* The box lo..hi grown by reach on every side. */
static void near_box(const double lo[3], const double hi[3], double reach,
                     double out_lo[3], double out_hi[3])
{
    int j;
    for (j = 0; j < 3; j++) {
        out_lo[j] = lo[j] - reach;
        out_hi[j] = hi[j] + reach;
    }
}

/* Points are first tried against the box that holds the arm's clearance so
 * far in blocks of QRT_CLEARANCE_BLOCK, in float over each axis (4 lanes):
 * most blocks of a scan hold no point near the arm, and most points of the
 * others are out of the box too. */

/* Mark in in[] the QRT_CLEARANCE_BLOCK entries from `at` on that are not out
 * of the box lo..hi, and tell how many. The box is of doubles and the test
 * in float, yet a point the test puts out is out of lo..hi: no float lies
 * strictly between a double and the float nearest it, so for a float x,
 * x < (float)lo gives x < lo, and x > (float)hi gives x > hi. (A bound past
 * float's range rounds to an infinity, for which the same holds; a NaN
 * bound puts no point out, as in the test of each point.) One loop of fixed
 * count and no branch: the compiler makes it 4 lanes wide. */
static int mark_in_box(const struct qrt_points *pts, long at,
                       const double lo[3], const double hi[3],
                       int in[QRT_CLEARANCE_BLOCK])
{
    float lo_x = (float)lo[0], lo_y = (float)lo[1], lo_z = (float)lo[2],
          hi_x = (float)hi[0], hi_y = (float)hi[1], hi_z = (float)hi[2];
    int j, count = 0;
    for (j = 0; j < QRT_CLEARANCE_BLOCK; j++) {
        float x = pts->x[at + j], y = pts->y[at + j], z = pts->z[at + j];
        in[j] = !((x < lo_x) | (x > hi_x) | (y < lo_y) | (y > hi_y) |
                  (z < lo_z) | (z > hi_z));
        count += in[j];
    }
    return count;
}

static long block_count(const struct qrt_points *pts)
{
    return (pts->count + QRT_CLEARANCE_BLOCK - 1) / QRT_CLEARANCE_BLOCK;
}

/* Block b's box. */
static void fill_block_box(const struct qrt_points *pts, long b, float box[6])
{
    long i = b * QRT_CLEARANCE_BLOCK,
         end = i + QRT_CLEARANCE_BLOCK < pts->count ? i + QRT_CLEARANCE_BLOCK
                                                    : pts->count,
         j;
    box[0] = box[3] = pts->x[i];
    box[1] = box[4] = pts->y[i];
    box[2] = box[5] = pts->z[i];
    for (j = i + 1; j < end; j++) {
        box[0] = pts->x[j] < box[0] ? pts->x[j] : box[0];
        box[1] = pts->y[j] < box[1] ? pts->y[j] : box[1];
        box[2] = pts->z[j] < box[2] ? pts->z[j] : box[2];
        box[3] = pts->x[j] > box[3] ? pts->x[j] : box[3];
        box[4] = pts->y[j] > box[4] ? pts->y[j] : box[4];
        box[5] = pts->z[j] > box[5] ? pts->z[j] : box[5];
    }
}

void qrt_points_block_boxes(const struct qrt_points *pts, float (*block_box)[6])
{
    long i, blocks = block_count(pts);
    /* after the blocks' boxes, each group's: the box of its blocks' */
    for (i = 0; i < blocks; i += QRT_CLEARANCE_GROUP) {
        float *group = block_box[blocks + i / QRT_CLEARANCE_GROUP];
        long end = i + QRT_CLEARANCE_GROUP < blocks ? i + QRT_CLEARANCE_GROUP
                                                    : blocks,
             b;
        int j;
        for (b = i; b < end; b++) {
            fill_block_box(pts, b, block_box[b]);
            for (j = 0; j < 3; j++) {
                if (b == i || block_box[b][j] < group[j])
                    group[j] = block_box[b][j];
                if (b == i || block_box[b][j + 3] > group[j + 3])
                    group[j + 3] = block_box[b][j + 3];
            }
        }
    }
}

/* Does the box lie wholly outside lo .. hi on some axis? (Then so does
 * every point in it.) */
static int box_outside(const float box[6], const double lo[3],
                       const double hi[3])
{
    return box[3] < lo[0] || box[0] > hi[0] || box[4] < lo[1] ||
           box[1] > hi[1] || box[5] < lo[2] || box[2] > hi[2];
}

/* Can a point of the block box lower best against some capsule of the
 * chain? Every stored point lies within its float bounds, so within the
 * box's half-diagonal of its centre (rounded up by a part in 10^6): a
 * capsule farther than best + that from the centre cannot come nearer. */
static int box_may_lower(const float box[6], const double (*p)[3],
                         const double *radius_m, int n, double best)
{
    double c[3], h2 = 0.0, h;
    int j, k;
    for (j = 0; j < 3; j++) {
        double half = 0.5 * ((double)box[j + 3] - (double)box[j]);
        c[j] = 0.5 * ((double)box[j + 3] + (double)box[j]);
        h2 += half * half;
    }
    h = sqrt(h2) * (1.0 + 1e-6) + 1e-9;
    for (k = 0; k < n; k++) {
        double reach = best + radius_m[k] + h;
        if (reach > 0.0 && qrt_seg_dist2(c, p[k], p[k + 1]) < reach * reach)
            return 1;
    }
    return 0;
}

double qrt_chain_clearance_capped(const double (*p)[3], const double *radius_m,
                                  int n, const struct qrt_points *pts,
                                  const float (*block_box)[6], double cap)
{
    struct qrt_point_axes ax = qrt_points_axes(pts);
    double lo[QRT_CHAIN_MAX][3], hi[QRT_CHAIN_MAX][3], arm_lo[3], arm_hi[3],
        near_lo[3], near_hi[3], best = cap, widest = radius_m[0];
    long i, blocks = block_count(pts), skip_to = 0;
    int k, j;
    for (k = 1; k < n; k++)
        if (radius_m[k] > widest)
            widest = radius_m[k];
    for (j = 0; j < 3; j++)
        arm_lo[j] = arm_hi[j] = p[0][j];
    for (k = 0; k < n; k++)
        for (j = 0; j < 3; j++) {
            lo[k][j] = p[k][j] < p[k + 1][j] ? p[k][j] : p[k + 1][j];
            hi[k][j] = p[k][j] > p[k + 1][j] ? p[k][j] : p[k + 1][j];
            if (p[k + 1][j] < arm_lo[j])
                arm_lo[j] = p[k + 1][j];
            if (p[k + 1][j] > arm_hi[j])
                arm_hi[j] = p[k + 1][j];
        }
    /* Most points lie far from the whole arm: one box around every
     * capsule, grown by the widest reach a capsule test below could use
     * now, turns them away with one test instead of n (grown again only
     * when best falls). */
    near_box(arm_lo, arm_hi, best + widest, near_lo, near_hi);
    for (i = 0; i < pts->count; i += QRT_CLEARANCE_BLOCK) {
        /* the marks are made with the box as it is at the block's start;
         * it only shrinks, so a point out of it then stays out */
        int in[QRT_CLEARANCE_BLOCK], m = QRT_CLEARANCE_BLOCK, b;
        long block = i / QRT_CLEARANCE_BLOCK;
        if (block < skip_to)
            continue;
        if (block_box != NULL) {
            /* a group wholly out of the near box: all its blocks out */
            if (block % QRT_CLEARANCE_GROUP == 0 &&
                box_outside(block_box[blocks + block / QRT_CLEARANCE_GROUP],
                            near_lo, near_hi)) {
                skip_to = block + QRT_CLEARANCE_GROUP;
                continue;
            }
            if (box_outside(block_box[block], near_lo, near_hi) ||
                !box_may_lower(block_box[block], p, radius_m, n, best))
                continue;
        }
        if (pts->count - i < QRT_CLEARANCE_BLOCK) {
            m = (int)(pts->count - i);
            for (b = 0; b < m; b++)
                in[b] = 1;
        } else if (mark_in_box(pts, i, near_lo, near_hi, in) == 0) {
            continue;
        }
        for (b = 0; b < m; b++) {
            double x[3];
            if (!in[b])
                continue;
            qrt_point_at(&ax, i + b, x);
            if (x[0] < near_lo[0] || x[0] > near_hi[0] || x[1] < near_lo[1] ||
                x[1] > near_hi[1] || x[2] < near_lo[2] || x[2] > near_hi[2])
                continue;
            for (k = 0; k < n; k++) {
                /* a point farther than best + radius from the capsule's
                 * box on some axis cannot lower best: skip the segment
                 * distance */
                double reach = best + radius_m[k], c;
                if (x[0] < lo[k][0] - reach || x[0] > hi[k][0] + reach ||
                    x[1] < lo[k][1] - reach || x[1] > hi[k][1] + reach ||
                    x[2] < lo[k][2] - reach || x[2] > hi[k][2] + reach)
                    continue;
                c = sqrt(qrt_seg_dist2(x, p[k], p[k + 1])) - radius_m[k];
                if (c < best) {
                    best = c;
                    near_box(arm_lo, arm_hi, best + widest, near_lo, near_hi);
                }
            }
            if (best <= 0.0)
                return best; /* colliding: how deep does not matter */
        }
    }
    return best;
}

int qrt_arm_capsules(const struct qrt_arm *arm, const double q_deg[3],
                     double extra_m, double (*p)[3], double *radius_m)
{
    int k, n = 3;
    qrt_arm_fk(arm, q_deg, p);
    for (k = 0; k < 3; k++)
        radius_m[k] = arm->link_radius_m[k] + extra_m;
    if (arm->tool_m > 0.0) {
        qrt_arm_tool_tip(arm, q_deg, p[4]);
        radius_m[3] = arm->tool_radius_m + extra_m;
        n = 4;
    }
    return n;
}

/* qrt_clearance_capped, passing over the blocks of block_box (or none,
 * NULL) that lie out of reach. */
static double clearance_boxed(const struct qrt_arm *arm,
                              const double radius_m[3],
                              const struct qrt_points *pts,
                              const float (*block_box)[6], const double q[3],
                              double cap)
{
    double p[4][3];
    qrt_arm_fk(arm, q, p);
    return qrt_chain_clearance_capped((const double(*)[3])p, radius_m, 3, pts,
                                      block_box, cap);
}

double qrt_clearance_capped(const struct qrt_arm *arm, const double radius_m[3],
                            const struct qrt_points *pts, const double q_deg[3],
                            double cap)
{
    return clearance_boxed(arm, radius_m, pts, NULL, q_deg, cap);
}

double qrt_clearance(const struct qrt_arm *arm, const double radius_m[3],
                     const struct qrt_points *pts, const double q_deg[3])
{
    return qrt_clearance_capped(arm, radius_m, pts, q_deg, 1e30);
}

/* Advancement on a blocked motion crawls ever closer to the contact, one
 * clearance over all points per step. After witness_after steps it looks
 * for a witness instead: a colliding configuration among QRT_WITNESS_SAMPLES
 * samples, taken coarse to fine (the far end first, then the middle, the
 * quarters, ...), decides the motion. Advancement could never have passed
 * a colliding configuration, so the answer is the same, only sooner. */

static int has_witness(const struct qrt_arm *arm, const double radius_m[3],
                       const struct qrt_points *pts,
                       const float (*block_box)[6], const double a_deg[3],
                       const double d[3])
{
    int level, k, j;
    for (level = 1; level <= QRT_WITNESS_SAMPLES; level *= 2)
        for (k = 1; k <= level; k += 2) { /* s = k / level, new ones only */
            double q[3], s = (double)k / level;
            for (j = 0; j < 3; j++)
                q[j] = a_deg[j] + s * d[j];
            if (clearance_boxed(arm, radius_m, pts, block_box, q, 2e-7) <= 1e-7)
                return 1;
        }
    return 0;
}

int qrt_motion_collides_at(const struct qrt_arm *arm, const double radius_m[3],
                           const struct qrt_points *pts,
                           const struct qrt_lattice *lat, const double a_deg[3],
                           const double b_deg[3], double t)
{
    double d[3], q[3];
    int j;
    qrt_motion_delta(lat, a_deg, b_deg, d);
    for (j = 0; j < 3; j++)
        q[j] = a_deg[j] + t * d[j];
    /* the witness test of has_witness */
    return qrt_clearance_capped(arm, radius_m, pts, q, 2e-7) <= 1e-7;
}

int qrt_motion_free_exact(const struct qrt_arm *arm, const double radius_m[3],
                          const struct qrt_points *pts,
                          const float (*block_box)[6],
                          const struct qrt_lattice *lat, const double a_deg[3],
                          const double b_deg[3], int max_steps,
                          int witness_after)
{
    double d[3], link_speed[3], speed, t = 0.0;
    int step, j;
    qrt_motion_delta(lat, a_deg, b_deg, d);
    /* No point of the arm moves faster than link 3's fastest. */
    qrt_motion_link_speeds(arm, d, link_speed);
    speed = link_speed[2];
    for (step = 0; step < max_steps; step++) {
        double q[3], c, cap;
        if (step == witness_after &&
            has_witness(arm, radius_m, pts, block_box, a_deg, d))
            return 0;
        for (j = 0; j < 3; j++)
            q[j] = a_deg[j] + t * d[j];
        /* clearance beyond what carries the arm to b is never needed: a
         * lower bound is as good as the value for the step; with block
         * boxes, capping it lower lets whole blocks be passed over, for a
         * few more steps */
        cap = speed * (1.0 - t) * 1.01 + 1e-6;
        if (block_box != NULL && cap > QRT_BOXED_STEP_CAP_M)
            cap = QRT_BOXED_STEP_CAP_M;
        c = clearance_boxed(arm, radius_m, pts, block_box, q, cap);
        if (c <= 1e-7)
            return 0;
        if (speed <= 0.0)
            return 1;
        t += c / speed;
        if (t >= 1.0)
            return 1;
    }
    return 0;
}
