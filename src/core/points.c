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

static float voxel_centre(long v, double voxel_m)
{
    return (float)(((double)v + 0.5) * voxel_m);
}

static void store_centre(struct qrt_points *pts, long i, const long v[3])
{
    pts->x[i] = voxel_centre(v[0], pts->voxel_m);
    pts->y[i] = voxel_centre(v[1], pts->voxel_m);
    pts->z[i] = voxel_centre(v[2], pts->voxel_m);
}

static void store_point(struct qrt_points *pts, long i, const double p[3])
{
    pts->x[i] = (float)p[0];
    pts->y[i] = (float)p[1];
    pts->z[i] = (float)p[2];
}

/* Move every entry onto the centre of its voxel at edge voxel_m, merging
 * entries that share a voxel. Grids are nested (each edge doubles the
 * last, same origin), so a point's new voxel contains its old one. */
static void requantise(struct qrt_points *pts, double voxel_m)
{
    long i, n = pts->count;
    long s;
    pts->voxel_m = voxel_m;
    for (s = 0; s < QRT_POINT_HASH_SLOTS; s++)
        pts->hash[s] = 0;
    pts->count = 0;
    for (i = 0; i < n; i++) {
        long v[3];
        uint32_t slot;
        entry_voxel(pts, i, v); /* on the new grid: voxel_m is set */
        if (find_voxel(pts, v, &slot) >= 0)
            continue;
        store_centre(pts, pts->count, v);
        pts->hash[slot] = (uint32_t)(pts->count + 1);
        pts->count++;
    }
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
        long v[3];
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
        for (k = 0; k < 3; k++)
            v[k] = voxel_coord(p[k], pts->voxel_m);
        if (find_voxel(pts, v, &slot) >= 0)
            return;
        if (pts->count < QRT_MAX_POINTS) {
            store_centre(pts, pts->count, v);
            pts->hash[slot] = (uint32_t)(pts->count + 1);
            pts->count++;
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
    pts->reach_m = reach_m;
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
                     double r2, long *count, long *far)
{
    long i, next = *count;
    for (i = 0; i < m; i++) {
        const double *p = xyz + 3 * i;
        if (!(p[0] * p[0] + p[1] * p[1] + p[2] * p[2] <= r2)) {
            if (!finite_point(p))
                return QRT_E_INVALID;
            (*far)++;
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
    double r2 = pts->reach_m * pts->reach_m;
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
        if (keep_near(pts, xyz + 3 * i, m, r2, &count, &far) != QRT_OK)
            return QRT_E_INVALID;
    }
    pts->count = count;
    pts->received += n;
    pts->ignored_far += far;
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
        pts->received++;
        if (p[0] * p[0] + p[1] * p[1] + p[2] * p[2] > r2) {
            pts->ignored_far++;
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
    return 0.5 * sqrt(3.0) * pts->voxel_m + rounding + 1e-9;
}
