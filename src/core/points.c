/* Obstacle point table with adaptive voxel quantisation (see points.h). */
#include "qrtplan/points.h"

#include <math.h>

#include "qrtplan/status.h"

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
    int k;
    for (k = 0; k < 3; k++)
        v[k] = voxel_coord(pts->xyz[i][k], pts->voxel_m);
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

static void store_centre(struct qrt_points *pts, long i, const long v[3])
{
    int k;
    for (k = 0; k < 3; k++)
        pts->xyz[i][k] = (float)(((double)v[k] + 0.5) * pts->voxel_m);
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
        int k;
        for (k = 0; k < 3; k++)
            v[k] = voxel_coord(pts->xyz[i][k], voxel_m);
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
                for (k = 0; k < 3; k++)
                    pts->xyz[pts->count][k] = (float)p[k];
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

/* Every point fits the table exactly: one pass checks and stores. A point
 * whose squared distance is not within reach is far or not finite (a NaN
 * fails every compare, an infinity is beyond reach), and only such a point
 * pays for the finite test. A batch with a non-finite coordinate leaves
 * the counters as they were; what it wrote past the count is never read.
 * (The finite test on every point, in a pass of its own, took over a
 * quarter of the intake.) */
static int add_exact(struct qrt_points *pts, const double *xyz, long n)
{
    float(*dst)[3] = pts->xyz; /* counters in locals: the stores into xyz */
    long count = pts->count, far = 0, i; /* would reload them each point */
    double r2 = pts->reach_m * pts->reach_m;
    for (i = 0; i < n; i++) {
        const double *p = xyz + 3 * i;
        double d2 = p[0] * p[0] + p[1] * p[1] + p[2] * p[2];
        if (!(d2 <= r2)) {
            if (!finite_point(p))
                return QRT_E_INVALID;
            far++;
            continue;
        }
        dst[count][0] = (float)p[0];
        dst[count][1] = (float)p[1];
        dst[count][2] = (float)p[2];
        count++;
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
