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

/* (inline: every point passes here, and without it GCC stopped inlining
 * it once the axes were read through ax: about 15 instructions a point) */
static inline void cube_of(const struct qrt_point_axes *ax, long i,
                           double inv_cell, long key[3])
{
    key[0] = qrt_floor((double)ax->x[i] * inv_cell);
    key[1] = qrt_floor((double)ax->y[i] * inv_cell);
    key[2] = qrt_floor((double)ax->z[i] * inv_cell);
}

/* A cube's key packed into 30 bits (10 per axis), or -1 when it does not
 * fit (then keys are compared whole): the walk below compares each point's
 * cube with its chain's without computing it again. One test for the three
 * axes: a key in [-512, 511] is one whose offset has no bit above bit 9. */
static int32_t packed(const long key[3])
{
    unsigned long x = (unsigned long)(key[0] + 512),
                  y = (unsigned long)(key[1] + 512),
                  z = (unsigned long)(key[2] + 512);
    if (((x | y | z) & ~1023UL) != 0)
        return -1;
    return (int32_t)((x << 20) | (y << 10) | z);
}

/* Do points a and b lie in the same cube? */
static int same_cube(const struct qrt_point_axes *ax, const int32_t *cube,
                     long a, long b, double inv_cell)
{
    long ka[3], kb[3];
    if (cube[a] >= 0 || cube[b] >= 0)
        return cube[a] == cube[b];
    cube_of(ax, a, inv_cell, ka);
    cube_of(ax, b, inv_cell, kb);
    return ka[0] == kb[0] && ka[1] == kb[1] && ka[2] == kb[2];
}

/* The slot of a packed key: Fibonacci hashing, the top log2(size) bits of
 * one 32-bit product (cubes that differ only in their low bits spread). */
static long slot_of_packed(int32_t key, int size_bits)
{
    return (long)(((uint32_t)key * 0x9E3779B1u) >> (32 - size_bits));
}

static long slot_of(const long key[3], long size)
{
    uint64_t h = (uint64_t)key[0] * 0x9E3779B97F4A7C15ULL;
    h ^= (uint64_t)key[1] * 0xC2B2AE3D27D4EB4FULL + (h >> 31);
    h ^= (uint64_t)key[2] * 0x165667B19E3779F9ULL + (h >> 29);
    h ^= h >> 32;
    return (long)(h & (uint64_t)(size - 1));
}

void qrt_cluster_points(const struct qrt_point_axes *ax, long n, double cell_m,
                        int max_members, int32_t *scratch,
                        qrt_cluster_visit visit, void *ctx)
{
    long size = table_size(n), i, s;
    int32_t *head = scratch, *next = scratch + size, *cube = next + n;
    int32_t members[64];
    double inv_cell = 1.0 / cell_m;
    int size_bits = 0;
    if (max_members > 64)
        max_members = 64;
    while ((1L << size_bits) < size)
        size_bits++;
    for (s = 0; s < size; s++)
        head[s] = -1;
    /* Which slot a cube takes decides only the order groups are visited
     * in, never which points share a group: a chain keeps its points in
     * reverse index order, whichever other cubes share it. */
    for (i = 0; i < n; i++) {
        long key[3];
        cube_of(ax, i, inv_cell, key);
        cube[i] = packed(key);
        s = cube[i] >= 0 ? slot_of_packed(cube[i], size_bits)
                         : slot_of(key, size);
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
                if (same_cube(ax, cube, e, first, inv_cell)) {
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

long qrt_cluster_count(const struct qrt_point_axes *ax, long n, double cell_m,
                       int max_members, int32_t *scratch)
{
    long groups = 0;
    qrt_cluster_points(ax, n, cell_m, max_members, scratch, count_group,
                       &groups);
    return groups;
}
