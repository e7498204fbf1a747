/* The point table in Morton order (see order.h): the keys sorted by a
 * radix sort, then the entries moved along the permutation's cycles. */
#include "order.h"

/* Cells per axis: 2^10 across the reach's cube, so about 2 mm for a 1 m
 * reach; the key has 30 bits, sorted 8 at a time (the constants are
 * written out: MISRA reads 1u as 8 bits wide, too narrow to shift). */
#define ORDER_CELLS 1024u
#define ORDER_RADIX 256
#define ORDER_PASSES 4 /* 4 x 8 bits cover the 30 */

long qrt_points_order_scratch_len(long n)
{
    return 2 * n;
}

/* v's low 10 bits moved to every third bit. */
static uint32_t spread(uint32_t v)
{
    v &= 0x3FFu;
    v = (v | (v << 16)) & 0x030000FFu;
    v = (v | (v << 8)) & 0x0300F00Fu;
    v = (v | (v << 4)) & 0x030C30C3u;
    v = (v | (v << 2)) & 0x09249249u;
    return v;
}

static uint32_t cell(float x, double lo, double inv_cell)
{
    double c = ((double)x - lo) * inv_cell;
    if (!(c > 0.0)) /* also NaN, which the table never holds */
        return 0u;
    if (c >= (double)(ORDER_CELLS - 1u))
        return ORDER_CELLS - 1u;
    return (uint32_t)c;
}

/* The key's digit of weight `weight` (1, 256, 65536 or 16777216). */
static uint32_t digit(int32_t key, uint32_t weight)
{
    return ((uint32_t)key / weight) % (uint32_t)ORDER_RADIX;
}

/* One stable counting pass on the keys' digit of weight `weight`. */
static void radix_pass(const int32_t *key, const int32_t *idx, int32_t *key_out,
                       int32_t *idx_out, long n, uint32_t weight)
{
    long count[ORDER_RADIX], i, sum = 0;
    int b;
    for (b = 0; b < ORDER_RADIX; b++)
        count[b] = 0;
    for (i = 0; i < n; i++)
        count[digit(key[i], weight)]++;
    for (b = 0; b < ORDER_RADIX; b++) {
        long c = count[b];
        count[b] = sum;
        sum += c;
    }
    for (i = 0; i < n; i++) {
        long at = count[digit(key[i], weight)]++;
        key_out[at] = key[i];
        idx_out[at] = idx[i];
    }
}

/* One entry of the table, held while its place is overwritten. */
struct saved_entry {
    float x, y, z;
    uint8_t lo[3], hi[3];
};

static void save(const struct qrt_points *pts, long i, struct saved_entry *s)
{
    int k;
    s->x = pts->x[i];
    s->y = pts->y[i];
    s->z = pts->z[i];
    for (k = 0; k < 3; k++) {
        s->lo[k] = pts->box_lo[k][i];
        s->hi[k] = pts->box_hi[k][i];
    }
}

static void restore(struct qrt_points *pts, long i, const struct saved_entry *s)
{
    int k;
    pts->x[i] = s->x;
    pts->y[i] = s->y;
    pts->z[i] = s->z;
    for (k = 0; k < 3; k++) {
        pts->box_lo[k][i] = s->lo[k];
        pts->box_hi[k][i] = s->hi[k];
    }
}

void qrt_points_order(struct qrt_points *pts, int32_t *scratch_a,
                      int32_t *scratch_b)
{
    long n = pts->count, i;
    /* each radix pass reads one pair of arrays and writes the other */
    int32_t *key = scratch_a, *key2 = scratch_b; /* < 2^30 */
    int32_t *idx = scratch_a + n, *idx2 = scratch_b + n;
    double lo = -pts->reach_m,
           inv_cell = (double)ORDER_CELLS / (2.0 * pts->reach_m);
    uint32_t weight = 1u;
    int pass;
    if (n < 2 || !(pts->reach_m > 0.0)) { /* nothing moves */
        for (i = 0; i < n; i++)
            scratch_a[i] = (int32_t)i;
        return;
    }
    for (i = 0; i < n; i++) {
        key[i] = (int32_t)(spread(cell(pts->x[i], lo, inv_cell)) |
                           (spread(cell(pts->y[i], lo, inv_cell)) << 1) |
                           (spread(cell(pts->z[i], lo, inv_cell)) << 2));
        idx[i] = (int32_t)i;
    }
    for (pass = 0; pass < ORDER_PASSES; pass++) {
        int32_t *tk, *ti;
        radix_pass(key, idx, key2, idx2, n, weight);
        weight *= (uint32_t)ORDER_RADIX;
        tk = key;
        key = key2;
        key2 = tk;
        ti = idx;
        idx = idx2;
        idx2 = ti;
    }
    /* place i takes old entry idx[i]: follow each cycle once, marking a
     * place done by storing -1 - idx */
    for (i = 0; i < n; i++) {
        struct saved_entry s, moved;
        long j = i;
        if (idx[i] < 0)
            continue;
        save(pts, i, &s);
        for (;;) {
            long from = idx[j];
            idx[j] = (int32_t)(-1 - from);
            if (from == i) {
                restore(pts, j, &s);
                break;
            }
            save(pts, from, &moved);
            restore(pts, j, &moved);
            j = from;
        }
    }
    /* where each entry went, in the first n entries of scratch_a (the
     * keys are done with); in voxel mode the hash names entries by
     * place + 1 */
    for (i = 0; i < n; i++)
        scratch_a[-1 - idx[i]] = (int32_t)i;
    if (pts->voxel_m > 0.0) {
        long s;
        for (s = 0; s < QRT_POINT_HASH_SLOTS; s++)
            if (pts->hash[s] != 0u)
                pts->hash[s] = (uint32_t)scratch_a[pts->hash[s] - 1u] + 1u;
    }
}
