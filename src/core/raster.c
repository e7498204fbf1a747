/* Conservative T-space -> C-space conversion.
 *
 * For each point the paper's analytic reading (Eqs. 1-11) is used: link 1
 * sweeps a horizontal disc as alpha turns; links 2 and 3 lie in the
 * vertical half-plane at alpha, where the point is a disc seen from the
 * shoulder P1. For each alpha node whose cell box can bring the plane
 * within a radius of the point, the point is replaced by a disc in that
 * plane that contains every position the point takes relative to the arm
 * over the box; the angular interval of link 2 (sigma) and of link 3
 * (psi = sigma + eta) that comes within that disc follows in closed form.
 * Every approximation makes the blocked set larger, never smaller; see
 * docs/conservative-raster.md for the argument.
 */
#include "raster.h"

#include <math.h>
#include <stddef.h>

#include "bits.h"
#include "fastmath.h"
#include "geom.h"

/* radians added to every angular result: covers rounding and the fast
 * atan2's error (twice: a centre and a half-width each carry it) */
#define ANG_EPS (2.0 * QRT_FAST_ANGLE_ERR + 1e-9)

/* Half-width of the set of angles theta for which a segment of length len
 * from the origin at angle theta comes within reach of a point at distance
 * d (at angle 0): the set is |theta| <= result. Returns a negative value if
 * no angle does, a value > pi if every angle does. The distance grows
 * monotonically with |theta|, which is what makes this an interval. */
static double sweep_half_width(double d, double len, double reach)
{
    double tangent, c;
    if (d <= reach)
        return 4.0;
    tangent = sqrt(d * d - reach * reach);
    if (tangent <= len) /* asin(reach / d) */
        return qrt_fast_atan2(reach, tangent) + ANG_EPS;
    c = (d * d + len * len - reach * reach) / (2.0 * d * len);
    if (c >= 1.0)
        return -1.0;
    return qrt_fast_atan2(sqrt(1.0 - c * c), c) + ANG_EPS; /* acos(c) */
}

/* Bits a..b of a row (a <= b). */
static void set_row_range(uint64_t *row, int a, int b)
{
    int wa = a >> 6, wb = b >> 6, w;
    uint64_t first = ~0ULL << (a & 63), last = ~0ULL >> (63 - (b & 63));
    if (wa == wb) {
        row[wa] |= first & last;
        return;
    }
    row[wa] |= first;
    for (w = wa + 1; w < wb; w++)
        row[w] = ~0ULL;
    row[wb] |= last;
}

/* i modulo n, in [0, n). The callers' angles lie within a turn or so of
 * the axis, so one add or subtract nearly always does it: a 64-bit
 * division is tens of cycles, and this runs for every point near link 1
 * and every cluster's alpha window. */
static long wrap_index(long i, long n)
{
    if (i < 0)
        i += n;
    else if (i >= n)
        i -= n;
    return i >= 0 && i < n ? i : ((i % n) + n) % n;
}

/* Index ranges [out[i][0], out[i][1]] of the nodes of axis ax whose angle
 * lies within half of centre, modulo 2 pi. Returns the count (at most 3):
 * axes that do not wrap span at most 2 pi (qrt_arm_validate). */
static int angle_ranges(const struct qrt_axis *ax, double centre, double half,
                        int out[3][2])
{
    const double turn = 2.0 * QRT_PI, inv_turn = 1.0 / (2.0 * QRT_PI);
    int count = 0;
    long k, k_end;
    if (half >= QRT_PI) {
        out[0][0] = 0;
        out[0][1] = ax->n - 1;
        return 1;
    }
    if (ax->wraps) {
        long a = qrt_ceil((centre - half - ax->lo) * ax->inv_g);
        long b = qrt_floor((centre + half - ax->lo) * ax->inv_g);
        long ma, mb;
        if (b < a)
            return 0;
        if (b - a + 1 >= ax->n) {
            out[0][0] = 0;
            out[0][1] = ax->n - 1;
            return 1;
        }
        ma = wrap_index(a, ax->n);
        mb = wrap_index(b, ax->n);
        if (ma <= mb) {
            out[0][0] = (int)ma;
            out[0][1] = (int)mb;
            return 1;
        }
        out[0][0] = (int)ma;
        out[0][1] = ax->n - 1;
        out[1][0] = 0;
        out[1][1] = (int)mb;
        return 2;
    }
    /* the turns k for which centre + k turns can reach the axis */
    k = qrt_ceil((ax->lo - half - centre) * inv_turn);
    k_end = qrt_floor((ax->hi - 1e-12 + half - centre) * inv_turn);
    for (; k <= k_end && count < 3; k++) {
        double x = (centre + turn * (double)k - ax->lo) * ax->inv_g;
        double hw = half * ax->inv_g;
        long fa = qrt_ceil(x - hw), fb = qrt_floor(x + hw);
        if (fa < 0)
            fa = 0;
        if (fb > ax->n - 1)
            fb = ax->n - 1;
        if (fb < fa)
            continue;
        out[count][0] = (int)fa;
        out[count][1] = (int)fb;
        count++;
    }
    return count;
}

/* Is alpha node ia this raster's to write? */
static int owns(const struct qrt_raster *r, int ia)
{
    return (r->nparts <= 1 || ia % r->nparts == r->part) &&
           (r->only_alpha < 0 || ia == r->only_alpha) &&
           (!r->only_rows || r->alpha_wanted[ia]);
}

/* Is row (ia, is) one this raster must get right? */
static inline int wanted(const struct qrt_raster *r, int ia, int is)
{
    long bit = (long)ia * QRT_MAX_NS + is;
    if (r->only_alpha >= 0)
        return ia == r->only_alpha && is >= r->only_s0 && is < r->only_s1;
    return !r->only_rows || qrt_bit_test(r->only_rows, bit);
}

static void block_alpha(const struct qrt_raster *r, int ia)
{
    const struct qrt_lattice *lat = &r->mask->lat;
    int is;
    if (!owns(r, ia))
        return;
    for (is = 0; is < lat->n[1]; is++)
        set_row_range(r->mask->rows[ia][is], 0, lat->n[2] - 1);
}

void qrt_raster_setup(struct qrt_raster *r, struct qrt_mask *mask,
                      const struct qrt_arm *arm, const double radius_m[3],
                      double cspace_margin_deg, int part, int nparts)
{
    const struct qrt_lattice *lat = &mask->lat;
    int a, s, w, j;
    r->part = part;
    r->nparts = nparts;
    r->only_rows = NULL;
    r->only_alpha = -1;
    r->only_s0 = r->only_s1 = 0;
    r->arm = arm;
    r->mask = mask;
    r->g = lat->grid_deg * QRT_DEG;
    r->h = 0.5 * r->g + cspace_margin_deg * QRT_DEG + ANG_EPS;
    for (j = 0; j < 3; j++) {
        r->radius_m[j] = radius_m[j];
        r->lo[j] = lat->lo_deg[j] * QRT_DEG;
    }
    r->elbow_shift = 2.0 * arm->link_m[1] * sin(0.5 * r->h) * (1.0 + 1e-12);
    r->cos_h = cos(r->h);
    r->sin_h = sin(r->h);
    for (a = 0; a < lat->n[0]; a++) {
        double alpha = r->lo[0] + a * r->g;
        r->alpha_cs[a][0] = cos(alpha);
        r->alpha_cs[a][1] = sin(alpha);
    }
    for (j = 0; j < 3; j++) {
        r->axis[j].lo = r->lo[j];
        r->axis[j].inv_g = 1.0 / r->g;
        r->axis[j].n = lat->n[j];
        r->axis[j].hi = r->lo[j] + (lat->n[j] - 1) * r->g;
        r->axis[j].wraps = j == 0 && lat->alpha_wraps;
    }
    for (s = 0; s < lat->n[1]; s++) {
        double sigma = r->lo[1] + s * r->g;
        r->elbow[s][0] = arm->link_m[1] * cos(sigma);
        r->elbow[s][1] = arm->link_m[1] * sin(sigma);
    }
    for (w = 0; w < QRT_ROW_WORDS; w++)
        r->full_row[w] = 0;
    set_row_range(r->full_row, 0, lat->n[2] - 1);
    /* directions of the psi nodes j = is + ie, whose sectors span
     * psi_j +- 2h; the sector test needs that to be under half a turn */
    r->sector_ok = 4.0 * r->h < QRT_PI - 1e-6;
    for (j = 0; j + 1 < lat->n[1] + lat->n[2]; j++) {
        double psi = r->lo[1] + r->lo[2] + j * r->g;
        r->psi_edge[j][0] = (float)cos(psi - 2.0 * r->h);
        r->psi_edge[j][1] = (float)sin(psi - 2.0 * r->h);
        r->psi_edge[j][2] = (float)cos(psi + 2.0 * r->h);
        r->psi_edge[j][3] = (float)sin(psi + 2.0 * r->h);
    }
    /* a float direction is off by < 1e-7 rad, which moves no point of the
     * link by more than this */
    r->sector_eps = 2e-7 * (arm->link_m[2] + 1.0) + 1e-9;
}

void qrt_raster_begin(struct qrt_raster *r, struct qrt_mask *mask,
                      const struct qrt_arm *arm, const double radius_m[3],
                      double cspace_margin_deg)
{
    int a, s, w;
    for (a = 0; a < QRT_MAX_NA; a++)
        for (s = 0; s < QRT_MAX_NS; s++)
            for (w = 0; w < QRT_ROW_WORDS; w++)
                mask->rows[a][s][w] = 0;
    qrt_raster_setup(r, mask, arm, radius_m, cspace_margin_deg, 0, 1);
}

/* Link 1 depends on alpha only: a hit blocks whole alpha slabs. */
static void raster_link1(const struct qrt_raster *r, double rho,
                         const double p[3])
{
    double rad = r->radius_m[0], reach, w;
    int ranges[3][2], n, i, ia;
    if (fabs(p[2]) >= rad) /* most points: no atan2 needed */
        return;
    reach = sqrt(rad * rad - p[2] * p[2]) + 1e-12;
    w = sweep_half_width(rho, r->arm->link_m[0], reach);
    if (w < 0.0)
        return;
    n = angle_ranges(&r->axis[0], atan2(p[1], p[0]), w + r->h, ranges);
    for (i = 0; i < n; i++)
        for (ia = ranges[i][0]; ia <= ranges[i][1]; ia++)
            block_alpha(r, ia);
}

/* Extremes of sin and cos of the angle between the point's bearing and
 * alpha over alpha node ia's box, from the bearing's cosine and sine
 * relative to the node (no trig calls: rotations by +-h). */
static void trig_extremes(const struct qrt_raster *r, double cos_c,
                          double sin_c, double *abs_sin_min, double *cos_min,
                          double *cos_max)
{
    double c0 = cos_c * r->cos_h + sin_c * r->sin_h; /* cos(c - h) */
    double c1 = cos_c * r->cos_h - sin_c * r->sin_h; /* cos(c + h) */
    double s0 = fabs(sin_c * r->cos_h - cos_c * r->sin_h);
    double s1 = fabs(sin_c * r->cos_h + cos_c * r->sin_h);
    int has_zero = cos_c >= r->cos_h; /* |c| <= h */
    int has_pi = cos_c <= -r->cos_h;  /* pi - |c| <= h */
    *abs_sin_min = (has_zero || has_pi) ? 0.0 : (s0 < s1 ? s0 : s1);
    *cos_max = has_zero ? 1.0 : (c0 > c1 ? c0 : c1);
    *cos_min = has_pi ? -1.0 : (c0 < c1 ? c0 : c1);
}

/* A point (or a cluster's bounding ball) as seen in the arm's vertical
 * plane over the cell boxes of one alpha node: a disc centred (cu, z) from
 * the shoulder P1 at distance d, that every link-2 and link-3 contact must
 * come within reach2 / reach3 of. */
struct plane {
    struct qrti_disc dc; /* for link 3 (reach3 < 0 where it cannot touch) */
    double d, reach2;
    int hit2, hit3;
};

/* extra: added to both link radii (a cluster's ball radius). Returns
 * whether link 2 or link 3 can touch the point at this alpha node. */
static inline int plane_or_disc_at(const struct qrt_raster *r, int ia,
                                   const double p[3], double rho, double extra,
                                   int disc_only, struct plane *pl)
{
    double cos_c = 1.0, sin_c = 0.0, sin_min, cos_min, cos_max, v, spread, cu;
    double rad2 = r->radius_m[1] + extra, rad3 = r->radius_m[2] + extra;
    if (rho > 0.0) { /* the point's bearing relative to the node's alpha */
        cos_c = (p[0] * r->alpha_cs[ia][0] + p[1] * r->alpha_cs[ia][1]) / rho;
        sin_c = (p[1] * r->alpha_cs[ia][0] - p[0] * r->alpha_cs[ia][1]) / rho;
    }
    trig_extremes(r, cos_c, sin_c, &sin_min, &cos_min, &cos_max);
    v = rho * sin_min; /* nearest the point comes to the arm's plane */
    pl->hit2 = v < rad2;
    pl->hit3 = v < rad3;
    if (disc_only ? !pl->hit3 : !pl->hit2 && !pl->hit3)
        return 0;
    /* the point's radial coordinate seen from P1 spans cu +- spread; the
     * disc's centre is kept as floats, and both reaches grow by what that
     * rounding moved it */
    cu = 0.5 * rho * (cos_min + cos_max) - r->arm->link_m[0];
    spread = 0.5 * rho * (cos_max - cos_min);
    pl->dc.cu = (float)cu;
    pl->dc.z = (float)p[2];
    spread += fabs(cu - (double)pl->dc.cu) + fabs(p[2] - (double)pl->dc.z);
    pl->d = 0.0;
    pl->reach2 = 0.0;
    if (!disc_only) {
        pl->d =
            sqrt((double)pl->dc.cu * pl->dc.cu + (double)pl->dc.z * pl->dc.z);
        pl->reach2 = pl->hit2 ? sqrt(rad2 * rad2 - v * v) + spread : 0.0;
    }
    /* a float rounds off by under 2^-24 of itself: rounded up */
    pl->dc.reach3 =
        pl->hit3
            ? (float)((sqrt(rad3 * rad3 - v * v) + spread + r->elbow_shift) *
                      (1.0 + 2.4e-7))
            : -1.0f;
    return 1;
}

static int plane_at(const struct qrt_raster *r, int ia, const double p[3],
                    double rho, double extra, struct plane *pl)
{
    return plane_or_disc_at(r, ia, p, rho, extra, 0, pl);
}

/* Sigma rows link 2 can hit for this disc (whole rows: link 2 does not
 * depend on eta). Returns the count of index ranges. */
static int link2_rows(const struct qrt_raster *r, const struct plane *pl,
                      int ranges[3][2])
{
    double w;
    if (!pl->hit2)
        return 0;
    w = sweep_half_width(pl->d, r->arm->link_m[1], pl->reach2);
    if (w < 0.0)
        return 0;
    return angle_ranges(&r->axis[1], qrt_fast_atan2(pl->dc.z, pl->dc.cu),
                        w + r->h, ranges);
}

/* Link 2 (sigma only): rows it can hit are blocked whole. */
static void raster_link2(const struct qrt_raster *r, int ia,
                         const struct plane *pl, uint64_t *full)
{
    const struct qrt_lattice *lat = &r->mask->lat;
    int ranges[3][2], n = link2_rows(r, pl, ranges), i, is;
    for (i = 0; i < n; i++)
        for (is = ranges[i][0]; is <= ranges[i][1]; is++) {
            set_row_range(r->mask->rows[ia][is], 0, lat->n[2] - 1);
            qrt_bit_set(full, is);
        }
}

/* Are all rows of alpha node ia in the index ranges blocked for every eta?
 * (Every row, built or not: a row blocked whole stays so.) */
static int rows_full(const struct qrt_raster *r, int ia, int ranges[3][2],
                     int n)
{
    int i, is, w;
    for (i = 0; i < n; i++)
        for (is = ranges[i][0]; is <= ranges[i][1]; is++)
            for (w = 0; w < QRT_ROW_WORDS; w++)
                if ((r->mask->rows[ia][is][w] & r->full_row[w]) !=
                    r->full_row[w])
                    return 0;
    return 1;
}

/* Sigma rows whose elbow lies within link 3 (plus reach) of the disc. */
static int link3_rows(const struct qrt_raster *r, const struct plane *pl,
                      int rows[3][2])
{
    const double l2 = r->arm->link_m[1];
    double far = r->arm->link_m[2] + pl->dc.reach3, c;
    if (!pl->hit3 || pl->d > l2 + far)
        return 0;
    c = pl->d > 0.0 ? (pl->d * pl->d + l2 * l2 - far * far) / (2.0 * pl->d * l2)
                    : -2.0;
    if (c <= -1.0) /* law of cosines: every elbow position is near enough */
        return angle_ranges(&r->axis[1], 0.0, 4.0, rows);
    return angle_ranges(&r->axis[1], qrt_fast_atan2(pl->dc.z, pl->dc.cu),
                        qrt_fast_atan2(sqrt(1.0 - c * c), c) + ANG_EPS, rows);
}

/* Link 3 on sigma row is: the eta nodes whose psi = sigma + eta range
 * (+-2h over the box) meets the angles where link 3 comes within reach. */
static int link3_row_ranges(const struct qrt_raster *r, int is,
                            const struct qrti_disc *dc, int ranges[3][2])
{
    double du = dc->cu - r->elbow[is][0], dz = dc->z - r->elbow[is][1];
    double w = sweep_half_width(sqrt(du * du + dz * dz), r->arm->link_m[2],
                                dc->reach3);
    if (w < 0.0)
        return 0;
    return angle_ranges(&r->axis[2],
                        qrt_fast_atan2(dz, du) - (r->lo[1] + is * r->g),
                        w + 2.0 * r->h, ranges);
}

static void mark_ranges(uint64_t *row, int ranges[3][2], int n)
{
    int i;
    for (i = 0; i < n; i++)
        set_row_range(row, ranges[i][0], ranges[i][1]);
}

/* A disc (a member's plane) as seen from the elbow of one sigma row: its
 * centre w relative to the elbow and the reach link 3 must come within
 * (plus the float directions' error). */
struct elbow_view {
    double wu, wz, reach;
};

/* 0: link 3 cannot reach the disc for any psi; 2: it touches it for every
 * psi; 1: it depends on psi (v is filled in). */
static inline int view_from(const struct qrt_raster *r, double eu, double ez,
                            const struct qrti_disc *dc, struct elbow_view *v)
{
    double far, d2;
    v->wu = dc->cu - eu;
    v->wz = dc->z - ez;
    v->reach = dc->reach3 + r->sector_eps;
    d2 = v->wu * v->wu + v->wz * v->wz;
    far = r->arm->link_m[2] + v->reach;
    if (d2 > far * far)
        return 0;
    if (d2 <= v->reach * v->reach)
        return 2;
    return 1;
}

static inline int view_from_elbow(const struct qrt_raster *r, int is,
                                  const struct qrti_disc *dc,
                                  struct elbow_view *v)
{
    return view_from(r, r->elbow[is][0], r->elbow[is][1], dc, v);
}

/* The edges of the sector link 3 sweeps over psi nodes j0 .. j1: the start
 * of j0's and the end of j1's. */
static inline void sector_edges(const struct qrt_raster *r, int j0, int j1,
                                double edge[4])
{
    edge[0] = r->psi_edge[j0][0];
    edge[1] = r->psi_edge[j0][1];
    edge[2] = r->psi_edge[j1][2];
    edge[3] = r->psi_edge[j1][3];
}

/* Does the sector between the edges (radius L3 from the elbow, spanning
 * less than half a turn) come within v->reach of the disc? Asked only
 * where view_from_elbow said 1. */
static inline int sector_meets(const struct qrt_raster *r, const double edge[4],
                               const struct elbow_view *v)
{
    const double len = r->arm->link_m[2];
    /* how far the disc's centre lies inside each edge's line (the edges
     * are unit vectors to within 2e-7, hence the slack) */
    double inside[2], out = -v->reach * (1.0 + 1e-6);
    int k;
    inside[0] = edge[0] * v->wz - edge[1] * v->wu;
    inside[1] = v->wu * edge[3] - v->wz * edge[2];
    if (inside[0] >= 0.0 && inside[1] >= 0.0)
        return 1; /* between the edges, and within len + reach */
    /* the sector lies inside both lines: a disc beyond one misses it */
    if (inside[0] < out || inside[1] < out)
        return 0;
    for (k = 0; k < 2; k++) { /* else the edge segment it is outside of */
        double eu = edge[2 * k], ez = edge[2 * k + 1];
        double t = v->wu * eu + v->wz * ez, du, dz;
        if (inside[k] >= 0.0)
            continue;
        t = t < 0.0 ? 0.0 : (t > len ? len : t);
        du = v->wu - t * eu;
        dz = v->wz - t * ez;
        if (du * du + dz * dz <= v->reach * v->reach)
            return 1;
    }
    return 0;
}

/* The eta nodes of row is that the sector test (node_meets) may find
 * within reach of disc dc: link3_row_ranges with the reach widened past the
 * test's slack (sector_eps twice, and 1e-6 m for the factor on its
 * rejections) and the half-width by 1e-6 rad (its float directions are off
 * by under 2e-7 rad), so that these ranges hold every node the test
 * blocks and the ranges only save work, never decide. */
static int link3_row_candidates(const struct qrt_raster *r, int is,
                                const struct qrti_disc *dc, int ranges[3][2])
{
    double du = dc->cu - r->elbow[is][0], dz = dc->z - r->elbow[is][1];
    double reach = dc->reach3 + 2.0 * r->sector_eps + 1e-6;
    double w =
        sweep_half_width(sqrt(du * du + dz * dz), r->arm->link_m[2], reach);
    if (w < 0.0)
        return 0;
    return angle_ranges(&r->axis[2],
                        qrt_fast_atan2(dz, du) - (r->lo[1] + is * r->g),
                        w + 2.0 * r->h + 1e-6, ranges);
}

/* Does link 3 on node (is, ie), psi anywhere in psi_j +- 2h, come within
 * reach of the disc seen from the elbow as (seen, v)? The one test that
 * decides every link-3 bit where the sector test holds (r->sector_ok), so
 * that a node's bit is a function of the node and the points alone: rows
 * built whole and nodes asked one at a time agree bit for bit. */
static int node_meets(const struct qrt_raster *r, int is, int ie, int seen,
                      const struct elbow_view *v)
{
    double edge[4];
    if (seen != 1)
        return seen == 2;
    sector_edges(r, is + ie, is + ie, edge);
    return sector_meets(r, edge, v);
}

/* The open nodes of the ranges, as a set. */
static void open_set(const uint64_t *row, int ranges[3][2], int n,
                     uint64_t open[QRT_ROW_WORDS])
{
    int i, w;
    for (w = 0; w < QRT_ROW_WORDS; w++)
        open[w] = 0;
    for (i = 0; i < n; i++)
        set_row_range(open, ranges[i][0], ranges[i][1]);
    for (w = 0; w < QRT_ROW_WORDS; w++)
        open[w] &= ~row[w];
}

/* Any bit lo .. hi - 1 of the set, each taken flipped by flip (~0: any
 * clear bit)? A word at a time. */
static int any_bit(const uint64_t *set, long lo, long hi, uint64_t flip)
{
    while (lo < hi) {
        long w = lo >> 6, end = (w + 1) << 6;
        uint64_t bits = (set[w] ^ flip) >> (lo & 63);
        if (end > hi) /* only hi - lo of them */
            bits &= ~0ULL >> (64 - (hi - lo));
        if (bits)
            return 1;
        lo = end;
    }
    return 0;
}

/* The open nodes of row is, among disc dc's candidates, that node_meets
 * blocks for dc, into out; returns whether there are any. Where the sector
 * test holds only. */
static int disc_row_nodes(const struct qrt_raster *r, int is,
                          const struct qrti_disc *dc, const uint64_t *row,
                          uint64_t out[QRT_ROW_WORDS])
{
    struct elbow_view v;
    int ranges[3][2], n, w, seen;
    uint64_t any = 0;
    n = link3_row_candidates(r, is, dc, ranges);
    if (n == 0 || (seen = view_from_elbow(r, is, dc, &v)) == 0)
        return 0;
    open_set(row, ranges, n, out);
    for (w = 0; w < QRT_ROW_WORDS; w++) {
        uint64_t bits = out[w];
        for (; bits; bits &= bits - 1U) {
            int ie = (w << 6) + qrt_lowest_bit(bits);
            if (!node_meets(r, is, ie, seen, &v))
                qrt_bit_clear(out, ie);
        }
        any |= out[w];
    }
    return any != 0;
}

/* Link 3 of one disc (a point's, or a one-point cluster's ball) on row
 * is: every open node of its candidate ranges that node_meets blocks (each
 * whole range where the sector test does not hold). */
static void mark_disc_row(const struct qrt_raster *r, int is,
                          const struct qrti_disc *dc, uint64_t *row)
{
    uint64_t nodes[QRT_ROW_WORDS];
    int ranges[3][2], n, w;
    if (!r->sector_ok) {
        n = link3_row_ranges(r, is, dc, ranges);
        mark_ranges(row, ranges, n);
        return;
    }
    if (disc_row_nodes(r, is, dc, row, nodes))
        for (w = 0; w < QRT_ROW_WORDS; w++)
            row[w] |= nodes[w];
}

/* The nodes in ask (open nodes of row is that a cluster's ball blocks)
 * that a member blocks, by node_meets, member by member (a node set is
 * not asked again). A member whose disc misses the sector of all of them
 * by 1 um more than its reach misses each one, far beyond the test's
 * rounding, so it is not asked of each. */
static void mark_member_nodes(const struct qrt_raster *r, int is,
                              const uint64_t ask[QRT_ROW_WORDS],
                              const struct qrti_disc *md, int m, uint64_t *row)
{
    double all[4] = {0.0, 0.0, 0.0, 0.0};
    uint64_t left;
    int a = -1, b = -1, j, w, span_ok;
    for (w = 0; w < QRT_ROW_WORDS; w++)
        if (ask[w]) {
            if (a < 0)
                a = (w << 6) + qrt_lowest_bit(ask[w]);
            b = (w << 6) + qrt_highest_bit(ask[w]);
        }
    if (a < 0)
        return;
    span_ok = (b - a) * r->g + 4.0 * r->h < QRT_PI - 1e-6;
    if (span_ok)
        sector_edges(r, is + a, is + b, all);
    for (j = 0; j < m; j++) {
        struct elbow_view v;
        int seen;
        if (md[j].reach3 < 0.0)
            continue;
        seen = view_from_elbow(r, is, &md[j], &v);
        if (seen == 1 && span_ok) {
            struct elbow_view wide = v;
            wide.reach += 1e-6;
            if (!sector_meets(r, all, &wide))
                seen = 0;
        }
        if (seen == 0)
            continue;
        left = 0;
        for (w = 0; w < QRT_ROW_WORDS; w++) {
            uint64_t bits = ask[w] & ~row[w];
            for (; bits; bits &= bits - 1U) {
                int ie = (w << 6) + qrt_lowest_bit(bits);
                if (node_meets(r, is, ie, seen, &v))
                    qrt_bit_set(row, ie);
            }
            left |= ask[w] & ~row[w];
        }
        if (!left)
            return; /* every node asked is blocked */
    }
}

/* Links 2 and 3 of one point for the cell boxes of alpha node ia. */
static void raster_plane(const struct qrt_raster *r, int ia, double rho,
                         const double p[3])
{
    uint64_t full[QRTI_SIGMA_WORDS] = {0};
    struct plane pl;
    int rows[3][2], nrows, k, is;
    if (!plane_at(r, ia, p, rho, 0.0, &pl))
        return;
    raster_link2(r, ia, &pl, full);
    nrows = link3_rows(r, &pl, rows);
    for (k = 0; k < nrows; k++)
        for (is = rows[k][0]; is <= rows[k][1]; is++) {
            if (qrt_bit_test(full, is) || !wanted(r, ia, is))
                continue;
            mark_disc_row(r, is, &pl.dc, r->mask->rows[ia][is]);
        }
}

/* Alpha nodes (in up to 4 index ranges) whose boxes can bring the arm's
 * plane within rmax of a point at (rho, phi): alpha toward the point or
 * away from it, within the angle whose sine is rmax / rho. */
static int alpha_window(const struct qrt_raster *r, double rho, double phi,
                        double rmax, int ranges[6][2])
{
    /* phi may come from qrt_fast_atan2: its error is one of the two
     * QRT_FAST_ANGLE_ERR in ANG_EPS (asin is libm's, exact to rounding) */
    const struct qrt_lattice *lat = &r->mask->lat;
    int side, n = 0;
    if (rho <= rmax) {
        ranges[0][0] = 0;
        ranges[0][1] = lat->n[0] - 1;
        return 1;
    }
    for (side = 0; side < 2; side++)
        n += angle_ranges(&r->axis[0], phi + (side ? QRT_PI : 0.0),
                          asin(rmax / rho) + r->h + ANG_EPS, ranges + n);
    return n;
}

static double max_plane_radius(const struct qrt_raster *r)
{
    return r->radius_m[1] > r->radius_m[2] ? r->radius_m[1] : r->radius_m[2];
}

/* Links 2 and 3 of one point, over every alpha node its window holds. */
static void raster_planes(const struct qrt_raster *r, const double p[3],
                          double rho, double phi)
{
    int ranges[6][2], n, i, ia;
    n = alpha_window(r, rho, phi, max_plane_radius(r), ranges);
    for (i = 0; i < n; i++)
        for (ia = ranges[i][0]; ia <= ranges[i][1]; ia++)
            if (owns(r, ia))
                raster_plane(r, ia, rho, p);
}

void qrt_raster_point(const struct qrt_raster *r, const double p[3])
{
    double rho = sqrt(p[0] * p[0] + p[1] * p[1]);
    double phi = qrt_fast_atan2(p[1], p[0]); /* (alpha_window's ANG_EPS) */
    raster_link1(r, rho, p);
    raster_planes(r, p, rho, phi);
}

static void set_alpha_bits(const struct qrt_raster *r, double rho, double phi,
                           double reach, struct qrti_cluster_geom *g)
{
    int ranges[6][2], n, i, w;
    for (w = 0; w < QRTI_ALPHA_WORDS; w++)
        g->alpha[w] = 0;
    n = alpha_window(r, rho, phi, reach, ranges);
    for (i = 0; i < n; i++)
        set_row_range(g->alpha, ranges[i][0], ranges[i][1]);
}

void qrt_raster_cluster_prepare(const struct qrt_raster *r,
                                const struct qrt_point_axes *ax,
                                const int32_t *members, int m,
                                struct qrti_cluster_geom *g, double *mrho)
{
    double lo_x, lo_y, lo_z, hi_x, hi_y, hi_z, dx, dy, dz;
    int j;
    g->m = m;
    g->ball = 0.0;
    lo_x = hi_x = ax->x[members[0]];
    lo_y = hi_y = ax->y[members[0]];
    lo_z = hi_z = ax->z[members[0]];
    /* the axes written out, the box in scalars: every point of the cloud
     * passes here once, and arrays indexed by k stayed in memory */
    for (j = 0; j < m; j++) {
        double p[3];
        qrt_point_at(ax, members[j], p);
        lo_x = p[0] < lo_x ? p[0] : lo_x;
        hi_x = p[0] > hi_x ? p[0] : hi_x;
        lo_y = p[1] < lo_y ? p[1] : lo_y;
        hi_y = p[1] > hi_y ? p[1] : hi_y;
        lo_z = p[2] < lo_z ? p[2] : lo_z;
        hi_z = p[2] > hi_z ? p[2] : hi_z;
        mrho[j] = sqrt(p[0] * p[0] + p[1] * p[1]);
        if (fabs(p[2]) < r->radius_m[0]) /* (raster_link1's own first test) */
            raster_link1(r, mrho[j], p);
    }
    g->c[0] = 0.5 * (lo_x + hi_x);
    g->c[1] = 0.5 * (lo_y + hi_y);
    g->c[2] = 0.5 * (lo_z + hi_z);
    g->rho = sqrt(g->c[0] * g->c[0] + g->c[1] * g->c[1]);
    if (m == 1) { /* the point itself, as qrt_raster_point takes it */
        set_alpha_bits(r, g->rho, qrt_fast_atan2(g->c[1], g->c[0]),
                       max_plane_radius(r), g);
        return;
    }
    dx = hi_x - lo_x;
    dy = hi_y - lo_y;
    dz = hi_z - lo_z;
    /* the half-diagonal, summed in the axes' order */
    g->ball =
        sqrt(0.25 * dx * dx + 0.25 * dy * dy + 0.25 * dz * dz) * (1.0 + 1e-12) +
        1e-12;
    set_alpha_bits(r, g->rho, qrt_fast_atan2(g->c[1], g->c[0]),
                   max_plane_radius(r) + g->ball, g);
}

/* Member j's plane at alpha node ia; returns plane_at's answer. */
static int member_plane(const struct qrt_raster *r, int ia,
                        const struct qrt_point_axes *ax, const int32_t *members,
                        const double *mrho, int j, struct plane *pl)
{
    double p[3];
    qrt_point_at(ax, members[j], p);
    return plane_at(r, ia, p, mrho[j], 0.0, pl);
}

int qrt_raster_view_make(const struct qrt_raster *r,
                         const struct qrt_point_axes *ax,
                         const int32_t *members, const double *mrho,
                         const struct qrti_cluster_geom *g, int ia,
                         struct qrti_alpha_view *v)
{
    struct plane cpl;
    uint64_t full[QRTI_SIGMA_WORDS];
    int rows[3][2], nrows, i, w, m = g->m;
    for (w = 0; w < QRTI_SIGMA_WORDS; w++)
        v->rows[w] = full[w] = 0;
    if (!plane_at(r, ia, g->c, g->rho, m == 1 ? 0.0 : g->ball, &cpl))
        return 0; /* no member can touch links 2 or 3 here */
    if (m == 1) {
        raster_link2(r, ia, &cpl, full);
    } else {
        /* link 2: the members only where the ball's rows are not all
         * full; their rows are blocked whole, whichever row is built */
        nrows = link2_rows(r, &cpl, rows);
        if (nrows > 0 && !rows_full(r, ia, rows, nrows))
            for (i = 0; i < m; i++) {
                struct plane mp;
                if (member_plane(r, ia, ax, members, mrho, i, &mp))
                    raster_link2(r, ia, &mp, full);
            }
    }
    v->disc = cpl.dc;
    nrows = link3_rows(r, &cpl, rows);
    for (i = 0; i < nrows; i++)
        set_row_range(v->rows, rows[i][0], rows[i][1]);
    for (w = 0; w < QRTI_SIGMA_WORDS; w++)
        v->rows[w] &= ~full[w];
    return 1;
}

void qrt_raster_member_discs(const struct qrt_raster *r,
                             const struct qrt_point_axes *ax,
                             const int32_t *members, const double *mrho, int m,
                             int ia, struct qrti_disc *md)
{
    int j;
    for (j = 0; j < m; j++) { /* only link 3's disc (plane_at's dc) */
        struct plane pl;
        double p[3];
        qrt_point_at(ax, members[j], p);
        md[j].reach3 = -1.0f;
        if (plane_or_disc_at(r, ia, p, mrho[j], 0.0, 1, &pl))
            md[j] = pl.dc;
    }
}

static inline int view_row(const struct qrt_raster *r,
                           const struct qrti_alpha_view *v, int m, int ia,
                           int is, uint64_t ask[QRT_ROW_WORDS])
{
    uint64_t *row = r->mask->rows[ia][is];
    int ranges[3][2], n, w;
    uint64_t any = 0;
    if (!qrt_bit_test(v->rows, is))
        return 0;
    if (m == 1) { /* the point itself, as qrt_raster_point takes it */
        mark_disc_row(r, is, &v->disc, row);
        return 0;
    }
    if (!r->sector_ok) { /* every member's range where the ball's is open */
        n = link3_row_ranges(r, is, &v->disc, ranges);
        open_set(row, ranges, n, ask);
        for (w = 0; w < QRT_ROW_WORDS; w++)
            any |= ask[w];
        return n > 0 && any != 0;
    }
    return disc_row_nodes(r, is, &v->disc, row, ask);
}

static inline void view_members(const struct qrt_raster *r, int ia, int is,
                                const uint64_t ask[QRT_ROW_WORDS],
                                const struct qrti_disc *md, int m)
{
    uint64_t *row = r->mask->rows[ia][is];
    int j;
    if (r->sector_ok) {
        mark_member_nodes(r, is, ask, md, m, row);
        return;
    }
    for (j = 0; j < m; j++) {
        int ranges[3][2], n;
        if (md[j].reach3 < 0.0)
            continue;
        n = link3_row_ranges(r, is, &md[j], ranges);
        mark_ranges(row, ranges, n);
    }
}

int qrt_raster_view_row(const struct qrt_raster *r,
                        const struct qrti_alpha_view *v, int m, int ia, int is,
                        uint64_t ask[QRT_ROW_WORDS])
{
    return view_row(r, v, m, ia, is, ask);
}

void qrt_raster_view_members(const struct qrt_raster *r, int ia, int is,
                             const uint64_t ask[QRT_ROW_WORDS],
                             const struct qrti_disc *md, int m)
{
    view_members(r, ia, is, ask, md, m);
}

/* One node's sector, loaded once for many discs. */
struct node_sector {
    double e[4];   /* its edges */
    double eu, ez; /* the elbow */
};

static inline void node_sector_of(const struct qrt_raster *r, int is, int ie,
                                  struct node_sector *ns)
{
    sector_edges(r, is + ie, is + ie, ns->e);
    ns->eu = r->elbow[is][0];
    ns->ez = r->elbow[is][1];
}

/* node_meets(view_from_elbow(dc)) with the node's sector loaded once,
 * and sector_meets' rejection of a disc beyond one edge's line tried
 * first: it ends most of the tests a free node's query makes (the share is
 * in docs/performance.md). It gives what the full test gives: it is the same
 * sum, and a disc it rejects is neither out of link 3's reach (0 too) nor over
 * the elbow (view_from's 2), whose centre lies within reach of every line
 * through the elbow. */
static inline int disc_meets_node(const struct qrt_raster *r,
                                  const struct node_sector *ns,
                                  const struct qrti_disc *dc)
{
    struct elbow_view ev;
    double wu = dc->cu - ns->eu, wz = dc->z - ns->ez;
    double out = -(dc->reach3 + r->sector_eps) * (1.0 + 1e-6);
    int seen;
    if (ns->e[0] * wz - ns->e[1] * wu < out ||
        wu * ns->e[3] - wz * ns->e[2] < out)
        return 0;
    seen = view_from(r, ns->eu, ns->ez, dc, &ev);
    if (seen != 1)
        return seen == 2;
    return sector_meets(r, ns->e, &ev);
}

long qrt_raster_next_ball(const struct qrt_raster *r,
                          const struct qrti_alpha_view *views,
                          const uint64_t *row_views, long k, long n, int is,
                          int ie)
{
    const uint64_t row_bit = qrt_bit_mask(is);
    const int word = is >> 6;
    struct node_sector ns;
    long w;
    node_sector_of(r, is, ie, &ns);
    if (!row_views) {
        for (; k < n; k++)
            if ((views[k].rows[word] & row_bit) &&
                disc_meets_node(r, &ns, &views[k].disc))
                return k;
        return n;
    }
    /* only the views that reach the row: no branch on each view's row bit
     * (a quarter of them reach it, in no order a predictor learns) */
    for (w = k >> 6; k < n && w <= (n - 1) >> 6; w++) {
        uint64_t bits = row_views[w];
        if (w == k >> 6)
            bits &= ~0ULL << (k & 63);
        for (; bits; bits &= bits - 1U) {
            long j = (w << 6) + qrt_lowest_bit(bits);
            if (disc_meets_node(r, &ns, &views[j].disc))
                return j;
        }
    }
    return n;
}

int qrt_raster_node_members(const struct qrt_raster *r, int is, int ie,
                            const struct qrti_disc *md, int m)
{
    struct node_sector ns;
    int j;
    node_sector_of(r, is, ie, &ns);
    for (j = 0; j < m; j++)
        if (md[j].reach3 >= 0.0 && disc_meets_node(r, &ns, &md[j]))
            return 1;
    return 0;
}

/* A cluster of nearby points shares the link-3 work. Its bounding ball
 * (centre c, radius ball) touches the arm wherever any member does, so its
 * raster contains every cell a member truly blocks. On each sigma row the
 * ball's cells are computed once; when they are all blocked already, no
 * member can add a cell it truly blocks, and the members are skipped for
 * that row; otherwise each member is rastered on the row as usual. Dense
 * clouds block each cell hundreds of times over, so most rows are skipped.
 */
void qrt_raster_cluster_at(const struct qrt_raster *r,
                           const struct qrt_point_axes *ax,
                           const int32_t *members, const double *mrho,
                           const struct qrti_cluster_geom *g, int ia)
{
    struct qrti_alpha_view v;
    struct qrti_disc md[QRT_CLUSTER_MAX];
    uint64_t ask[QRT_ROW_WORDS];
    int discs_ready = 0, w;
    if (!owns(r, ia) || !qrt_bit_test(g->alpha, ia))
        return;
    if (!qrt_raster_view_make(r, ax, members, mrho, g, ia, &v))
        return;
    for (w = 0; w < QRTI_SIGMA_WORDS; w++) {
        uint64_t rows = v.rows[w]; /* the rows link 3 may reach, in order */
        for (; rows; rows &= rows - 1U) {
            int is = (w << 6) + qrt_lowest_bit(rows);
            if (!wanted(r, ia, is) || !view_row(r, &v, g->m, ia, is, ask))
                continue;
            if (!discs_ready) {
                qrt_raster_member_discs(r, ax, members, mrho, g->m, ia, md);
                discs_ready = 1;
            }
            view_members(r, ia, is, ask, md, g->m);
        }
    }
}

void qrt_raster_cluster(const struct qrt_raster *r,
                        const struct qrt_point_axes *ax, const int32_t *members,
                        int m)
{
    struct qrti_cluster_geom g;
    double mrho[QRT_CLUSTER_MAX];
    int j, ia;
    if (m > QRT_CLUSTER_MAX) {
        /* the clusterer never emits more, but every point must still count */
        for (j = 0; j < m; j++) {
            double p[3];
            qrt_point_at(ax, members[j], p);
            qrt_raster_point(r, p);
        }
        return;
    }
    if (m < 1)
        return;
    qrt_raster_cluster_prepare(r, ax, members, m, &g, mrho);
    for (ia = 0; ia < r->mask->lat.n[0]; ia++)
        if (qrt_bit_test(g.alpha, ia))
            qrt_raster_cluster_at(r, ax, members, mrho, &g, ia);
}

void qrt_raster_only_rows(struct qrt_raster *r, const uint64_t *rows)
{
    int ia;
    r->only_rows = rows;
    for (ia = 0; ia < r->mask->lat.n[0]; ia++) {
        long first = (long)ia * QRT_MAX_NS;
        r->alpha_wanted[ia] = 0;
        if (!rows || any_bit(rows, first, first + r->mask->lat.n[1], 0))
            r->alpha_wanted[ia] = 1;
    }
}

void qrt_raster_only_block(struct qrt_raster *r, int ia, int s0, int s1)
{
    r->only_alpha = ia;
    r->only_s0 = s0;
    r->only_s1 = s1;
}
