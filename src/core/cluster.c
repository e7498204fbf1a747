/* Bucketing points into cubes with a chained hash table (no sorting, no
 * allocation: the caller lends the scratch). */
#include "cluster.h"

#include <math.h>

#include "geom.h"

static long table_size(long n)
{
    long h = 16;
    while (h < n / 4)
        h *= 2;
    return h;
}

long qrt_cluster_scratch_len(long n)
{
    return table_size(n) + 2 * n;
}

static void cube_of(const float p[3], double inv_cell, long key[3])
{
    int k;
    for (k = 0; k < 3; k++)
        key[k] = qrt_floor((double)p[k] * inv_cell);
}

/* A cube's key packed into 30 bits (10 per axis), or -1 when it does not
 * fit (then keys are compared whole): the walk below compares each point's
 * cube with its chain's without computing it again. */
static int32_t packed(const long key[3])
{
    int k;
    for (k = 0; k < 3; k++)
        if (key[k] < -512 || key[k] > 511)
            return -1;
    return (int32_t)(((key[0] + 512) << 20) | ((key[1] + 512) << 10) |
                     (key[2] + 512));
}

/* Do points a and b lie in the same cube? */
static int same_cube(const float (*pts)[3], const int32_t *cube, long a, long b,
                     double inv_cell)
{
    long ka[3], kb[3];
    if (cube[a] >= 0 || cube[b] >= 0)
        return cube[a] == cube[b];
    cube_of(pts[a], inv_cell, ka);
    cube_of(pts[b], inv_cell, kb);
    return ka[0] == kb[0] && ka[1] == kb[1] && ka[2] == kb[2];
}

static long slot_of(const long key[3], long size)
{
    uint64_t h = (uint64_t)key[0] * 0x9E3779B97F4A7C15ULL;
    h ^= (uint64_t)key[1] * 0xC2B2AE3D27D4EB4FULL + (h >> 31);
    h ^= (uint64_t)key[2] * 0x165667B19E3779F9ULL + (h >> 29);
    h ^= h >> 32;
    return (long)(h & (uint64_t)(size - 1));
}

void qrt_cluster_points(const float (*pts)[3], long n, double cell_m,
                        int max_members, int32_t *scratch,
                        qrt_cluster_visit visit, void *ctx)
{
    long size = table_size(n), i, s;
    int32_t *head = scratch, *next = scratch + size, *cube = next + n;
    int32_t members[64];
    double inv_cell = 1.0 / cell_m;
    if (max_members > 64)
        max_members = 64;
    for (s = 0; s < size; s++)
        head[s] = -1;
    for (i = 0; i < n; i++) {
        long key[3];
        cube_of(pts[i], inv_cell, key);
        s = slot_of(key, size);
        cube[i] = packed(key);
        next[i] = head[s];
        head[s] = (int32_t)i;
    }
    /* A slot's chain may hold several cubes: take the first entry's cube,
     * unlink all its entries, visit them, and repeat until the chain is
     * empty. */
    for (s = 0; s < size; s++)
        while (head[s] >= 0) {
            long first = head[s], prev = -1, e = head[s];
            int m = 0;
            while (e >= 0) {
                long nxt = next[e];
                if (same_cube(pts, cube, e, first, inv_cell)) {
                    if (prev < 0)
                        head[s] = (int32_t)nxt;
                    else
                        next[prev] = (int32_t)nxt;
                    members[m++] = (int32_t)e;
                    if (m == max_members) {
                        visit(ctx, members, m);
                        m = 0;
                    }
                } else {
                    prev = e;
                }
                e = nxt;
            }
            if (m > 0)
                visit(ctx, members, m);
        }
}

double qrt_cluster_cell_for(long n, long groups)
{
    if (groups > 0 && n < (long)QRT_CLUSTER_SPARSE_MEAN * groups)
        return 2.0 * QRT_CLUSTER_CELL_M;
    return QRT_CLUSTER_CELL_M;
}

static void count_group(void *ctx, const int32_t *members, int m)
{
    (void)members;
    (void)m;
    ++*(long *)ctx;
}

long qrt_cluster_count(const float (*pts)[3], long n, double cell_m,
                       int max_members, int32_t *scratch)
{
    long groups = 0;
    qrt_cluster_points(pts, n, cell_m, max_members, scratch, count_group,
                       &groups);
    return groups;
}
