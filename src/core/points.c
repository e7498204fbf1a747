/* Obstacle point table with adaptive voxel quantisation (see points.h). */
#include "qrtplan/points.h"

#include <math.h>

#include "qrtplan/status.h"
#include "tuning.h"

static long voxel_coord(double x, double voxel_m)
{
    return (long)floor(x / voxel_m);
}

static uint32_t voxel_hash(long ix, long iy, long iz)
{
    uint64_t h = (uint64_t)ix * 0x9E3779B97F4A7C15ULL;
    h ^= (uint64_t)iy * 0xC2B2AE3D27D4EB4FULL + (h >> 29);
    h ^= (uint64_t)iz * 0x165667B19E3779F9ULL + (h >> 32);
    h ^= h >> 33;
    return (uint32_t)(h % (uint64_t)QRT_POINT_HASH_SLOTS);
}

static void entry_voxel(const struct qrt_points *pts, long i, long v[3])
{
    v[0] = voxel_coord(pts->x[i], pts->voxel_m);
    v[1] = voxel_coord(pts->y[i], pts->voxel_m);
    v[2] = voxel_coord(pts->z[i], pts->voxel_m);
}

/* Index of the entry in voxel v, or -1; *slot gets where it is or would go.
 * The table is at most half full, so the probe ends. */
static long find_voxel(const struct qrt_points *pts, const long v[3],
                       uint32_t *slot)
{
    uint32_t s = voxel_hash(v[0], v[1], v[2]);
    for (;;) {
        uint32_t e = pts->hash[s];
        long w[3];
        if (e == 0) {
            *slot = s;
            return -1;
        }
        entry_voxel(pts, (long)e - 1, w);
        if (w[0] == v[0] && w[1] == v[1] && w[2] == v[2]) {
            *slot = s;
            return (long)e - 1;
        }
        s = (s + 1u) % (uint32_t)QRT_POINT_HASH_SLOTS;
    }
}

/* A merged entry's box (points.h) is kept in steps of voxel_m /
 * QRT_VOXEL_BOX_STEPS. The entry stands at the box's centre, held at least
 * BOX_INSET steps inside its voxel: the voxel is read back from the stored
 * float position (entry_voxel), which that inset keeps out of reach of
 * float rounding (a 16th of a 1 mm voxel, 62 um, against 2^-24 of a
 * coordinate); the radius pays for the shift. */
#define BOX_INSET 16

/* A coordinate's bounds in steps from its voxel's low corner v * voxel_m:
 * rounded outwards (by more than the double arithmetic's error), inside
 * the voxel, at least a step apart. */
static void point_box(double x, long v, double voxel_m, uint8_t *lo,
                      uint8_t *hi)
{
    double t = (x - (double)v * voxel_m) / voxel_m * QRT_VOXEL_BOX_STEPS;
    long l = (long)floor(t - 1e-6), h = (long)ceil(t + 1e-6);
    if (l < 0)
        l = 0;
    if (l > QRT_VOXEL_BOX_STEPS - 1)
        l = QRT_VOXEL_BOX_STEPS - 1;
    if (h > QRT_VOXEL_BOX_STEPS)
        h = QRT_VOXEL_BOX_STEPS;
    if (h <= l)
        h = l + 1;
    *lo = (uint8_t)l;
    *hi = (uint8_t)h;
}

/* Store entry i at its box's centre in voxel v (held BOX_INSET steps
 * inside), and grow box_radius_m to the box's half-diagonal plus that
 * shift, so the ball round the stored position holds the box. */
static void store_box(struct qrt_points *pts, long i, const long v[3])
{
    double step = pts->voxel_m / QRT_VOXEL_BOX_STEPS, half2 = 0.0, shift2 = 0.0,
           c[3], r;
    int k;
    for (k = 0; k < 3; k++) {
        double mid = 0.5 * ((double)pts->box_lo[k][i] + pts->box_hi[k][i]);
        double at = mid < BOX_INSET ? BOX_INSET
                    : mid > QRT_VOXEL_BOX_STEPS - BOX_INSET
                        ? QRT_VOXEL_BOX_STEPS - BOX_INSET
                        : mid;
        double half = 0.5 * (pts->box_hi[k][i] - pts->box_lo[k][i]) * step;
        half2 += half * half;
        shift2 += (at - mid) * step * (at - mid) * step;
        c[k] = (double)v[k] * pts->voxel_m + at * step;
    }
    pts->x[i] = (float)c[0];
    pts->y[i] = (float)c[1];
    pts->z[i] = (float)c[2];
    r = sqrt(half2) + sqrt(shift2);
    if (r > pts->box_radius_m)
        pts->box_radius_m = r;
}

/* Grow entry i's box by the box lo..hi (steps, the same voxel). */
static void merge_box(struct qrt_points *pts, long i, const uint8_t lo[3],
                      const uint8_t hi[3])
{
    int k;
    for (k = 0; k < 3; k++) {
        if (lo[k] < pts->box_lo[k][i])
            pts->box_lo[k][i] = lo[k];
        if (hi[k] > pts->box_hi[k][i])
            pts->box_hi[k][i] = hi[k];
    }
}

static void store_point(struct qrt_points *pts, long i, const double p[3])
{
    pts->x[i] = (float)p[0];
    pts->y[i] = (float)p[1];
    pts->z[i] = (float)p[2];
}

/* Entry i's box (steps) on the grid of edge voxel_m, whose voxel v holds
 * it: from an exact point, or from a box on the grid of half that edge
 * (the grids are nested: each edge doubles the last, same origin, so the
 * old voxel lies in v, at offset 0 or one old edge on each axis), rounded
 * outwards. */
static void box_on_grid(const struct qrt_points *pts, long i, double old_m,
                        double voxel_m, const long v[3], uint8_t lo[3],
                        uint8_t hi[3])
{
    int k;
    const float *axis[3];
    axis[0] = pts->x;
    axis[1] = pts->y;
    axis[2] = pts->z;
    for (k = 0; k < 3; k++) {
        long off;
        if (old_m == 0.0) {
            point_box(axis[k][i], v[k], voxel_m, &lo[k], &hi[k]);
            continue;
        }
        off = (long)floor(axis[k][i] / old_m) - 2 * v[k]; /* 0 or 1 */
        lo[k] = (uint8_t)((off * QRT_VOXEL_BOX_STEPS + pts->box_lo[k][i]) / 2);
        hi[k] =
            (uint8_t)((off * QRT_VOXEL_BOX_STEPS + pts->box_hi[k][i] + 1) / 2);
    }
}

/* Merge every entry by voxel at edge voxel_m (from exact points, or from
 * the boxes at half that edge), each merged entry at its box's centre.
 * An entry is read before any write to its index: entries only move down. */
static void requantise(struct qrt_points *pts, double voxel_m)
{
    long i, n = pts->count;
    long s;
    double old_m = pts->voxel_m;
    for (s = 0; s < QRT_POINT_HASH_SLOTS; s++)
        pts->hash[s] = 0;
    pts->count = 0;
    pts->box_radius_m = 0.0;
    for (i = 0; i < n; i++) {
        long v[3], e;
        uint8_t lo[3], hi[3];
        uint32_t slot;
        int k;
        v[0] = voxel_coord(pts->x[i], voxel_m);
        v[1] = voxel_coord(pts->y[i], voxel_m);
        v[2] = voxel_coord(pts->z[i], voxel_m);
        box_on_grid(pts, i, old_m, voxel_m, v, lo, hi);
        pts->voxel_m = voxel_m; /* find_voxel reads the new grid */
        e = find_voxel(pts, v, &slot);
        if (e < 0) {
            e = pts->count++;
            pts->hash[slot] = (uint32_t)(e + 1);
            for (k = 0; k < 3; k++) {
                pts->box_lo[k][e] = lo[k];
                pts->box_hi[k][e] = hi[k];
            }
        } else {
            merge_box(pts, e, lo, hi);
        }
        store_box(pts, e, v);
        pts->voxel_m = old_m; /* entries from i on are still on the old */
    }
    pts->voxel_m = voxel_m;
}

/* Is every coordinate of p finite? x - x is 0 for a finite x and NaN for
 * an infinite or NaN one, and a NaN survives the sum: one compare a point
 * instead of three classifications. */
static int finite_point(const double p[3])
{
    return (p[0] - p[0]) + (p[1] - p[1]) + (p[2] - p[2]) == 0.0;
}

static int all_finite(const double *xyz, long n)
{
    long i;
    for (i = 0; i < n; i++)
        if (!finite_point(xyz + 3 * i))
            return 0;
    return 1;
}

static void add_one(struct qrt_points *pts, const double p[3])
{
    for (;;) {
        long v[3], e;
        uint8_t lo[3], hi[3];
        uint32_t slot;
        int k;
        if (pts->voxel_m == 0.0) {
            if (pts->count < QRT_MAX_POINTS) {
                store_point(pts, pts->count, p);
                pts->count++;
                return;
            }
            requantise(pts, QRT_VOXEL_BASE_M);
            continue;
        }
        for (k = 0; k < 3; k++) {
            v[k] = voxel_coord(p[k], pts->voxel_m);
            point_box(p[k], v[k], pts->voxel_m, &lo[k], &hi[k]);
        }
        e = find_voxel(pts, v, &slot);
        if (e >= 0) {
            merge_box(pts, e, lo, hi);
            store_box(pts, e, v);
            return;
        }
        if (pts->count < QRT_MAX_POINTS) {
            e = pts->count++;
            pts->hash[slot] = (uint32_t)(e + 1);
            for (k = 0; k < 3; k++) {
                pts->box_lo[k][e] = lo[k];
                pts->box_hi[k][e] = hi[k];
            }
            store_box(pts, e, v);
            return;
        }
        if (pts->voxel_m * 2.0 > QRT_VOXEL_MAX_M * 1.0000001) {
            pts->dropped++;
            return;
        }
        requantise(pts, pts->voxel_m * 2.0);
    }
}

void qrt_points_reset(struct qrt_points *pts, double reach_m)
{
    pts->count = 0;
    pts->received = 0;
    pts->ignored_far = 0;
    pts->dropped = 0;
    pts->voxel_m = 0.0;
    pts->box_radius_m = 0.0;
    pts->reach_m = reach_m;
    pts->far_min2 = QRT_NO_FAR_POINT;
}

/* Points are taken in blocks of QRT_INTAKE_BLOCK: a block is first stored and
 * checked in float, in two loops with no branch and a fixed count, which
 * the compiler turns into vector code even at -O2, and kept as it is when
 * every point of it is surely within reach. Else, and for a batch's last,
 * shorter block, each point is tested in double. After a block that was
 * not all near, only every QRT_INTAKE_RETRY-th block is tried in float: where
 * the reach cuts through the scan (a box's walls) most blocks are mixed,
 * and a float try of a mixed block is work thrown away. */

/* Store the QRT_INTAKE_BLOCK points at xyz as floats from entry `at` on and
 * tell whether every one is surely within reach: its stored float's
 * squared distance at most near2, which the caller sets under the squared
 * reach by more than float rounding can move it (see add_exact). A NaN
 * fails the compare and an infinity is beyond reach: such a block goes on
 * to keep_near. (The table's members are indexed directly: the compiler
 * knows that x, y and z do not overlap, and needs no check to vectorise.) */
static int store_block(struct qrt_points *pts, long at, const double *xyz,
                       float near2)
{
    int i, near = 0;
    for (i = 0; i < QRT_INTAKE_BLOCK; i++) {
        pts->x[at + i] = (float)xyz[3 * i];
        pts->y[at + i] = (float)xyz[3 * i + 1];
        pts->z[at + i] = (float)xyz[3 * i + 2];
    }
    for (i = 0; i < QRT_INTAKE_BLOCK; i++) {
        float x = pts->x[at + i], y = pts->y[at + i], z = pts->z[at + i];
        near += x * x + y * y + z * z <= near2 ? 1 : 0;
    }
    return near == QRT_INTAKE_BLOCK;
}

/* Store from entry *count on, in order, the points of xyz[0 .. 3m - 1]
 * within r2 of the base; *count grows by how many, *far by the rest.
 * QRT_E_INVALID if a coordinate is not finite: only a point not within
 * reach pays for that test. */
static int keep_near(struct qrt_points *pts, const double *xyz, long m,
                     double r2, long *count, long *far, double *far_min2)
{
    long i, next = *count;
    for (i = 0; i < m; i++) {
        const double *p = xyz + 3 * i;
        double d2 = p[0] * p[0] + p[1] * p[1] + p[2] * p[2];
        if (!(d2 <= r2)) {
            if (!finite_point(p))
                return QRT_E_INVALID;
            (*far)++;
            if (d2 < *far_min2)
                *far_min2 = d2;
            continue;
        }
        store_point(pts, next, p);
        next++;
    }
    *count = next;
    return QRT_OK;
}

/* Every point fits the table exactly. A batch with a non-finite coordinate
 * leaves the counters as they were; what it wrote past the count is never
 * read. (A pass of its own for the finite test took over a quarter of the
 * intake, and one branch a point on reach over a third.) */
static int add_exact(struct qrt_points *pts, const double *xyz, long n)
{
    long count = pts->count, far = 0, i;
    double r2 = pts->reach_m * pts->reach_m, far_min2 = pts->far_min2;
    /* A float of x is off by at most 2^-24 |x|, and its square and the sum
     * of three by as much again each: the float |q|^2 is within 2^-21 of
     * |p|^2, relative. Squares under 2^-126 may flush to 0, so near2 is 0
     * (no block all near) for a reach that small. */
    float near2 = r2 > 1e-30 ? (float)(r2 * (1.0 - 1e-5)) : 0.0f;
    int last_mixed = 0;
    for (i = 0; i < n; i += QRT_INTAKE_BLOCK) {
        long m = n - i < QRT_INTAKE_BLOCK ? n - i : QRT_INTAKE_BLOCK;
        if (m == QRT_INTAKE_BLOCK &&
            (!last_mixed || (i / QRT_INTAKE_BLOCK) % QRT_INTAKE_RETRY == 0)) {
            last_mixed = !store_block(pts, count, xyz + 3 * i, near2);
            if (!last_mixed) {
                count += m;
                continue;
            }
        }
        if (keep_near(pts, xyz + 3 * i, m, r2, &count, &far, &far_min2) !=
            QRT_OK)
            return QRT_E_INVALID;
    }
    pts->count = count;
    pts->received += n;
    pts->ignored_far += far;
    pts->far_min2 = far_min2;
    return QRT_OK;
}

int qrt_points_add(struct qrt_points *pts, const double *xyz, long n)
{
    long i;
    double r2 = pts->reach_m * pts->reach_m;
    if (n < 0 || (n > 0 && !xyz))
        return QRT_E_INVALID;
    if (pts->voxel_m == 0.0 && n <= QRT_MAX_POINTS - pts->count)
        return add_exact(pts, xyz, n);
    if (!all_finite(xyz, n))
        return QRT_E_INVALID;
    for (i = 0; i < n; i++) {
        const double *p = xyz + 3 * i;
        double d2 = p[0] * p[0] + p[1] * p[1] + p[2] * p[2];
        pts->received++;
        if (d2 > r2) {
            pts->ignored_far++;
            if (d2 < pts->far_min2)
                pts->far_min2 = d2;
            continue;
        }
        add_one(pts, p);
    }
    return QRT_OK;
}

double qrt_points_inflation_m(const struct qrt_points *pts)
{
    /* float keeps 24 bits: a stored coordinate is off by at most
     * |x| * 2^-24; reach_m bounds |x|. */
    double rounding = pts->reach_m * (1.0 / 4194304.0);
    return (pts->voxel_m > 0.0 ? pts->box_radius_m : 0.0) + rounding + 1e-9;
}
