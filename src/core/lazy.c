/* Mask rows built as they are read (see lazy.h). */
#include "lazy.h"

#include "cluster.h"
#include "raster.h"

/* Sigma rows built together: the search reads rows in bunches, and every
 * build visits each cluster that may block the alpha node once. */
#ifndef LAZY_BLOCK_ROWS
#define LAZY_BLOCK_ROWS 8
#endif

struct keep_ctx {
    struct qrt_planner *pl;
    const struct qrt_raster *r;
    long members;
    int ok;
};

/* Keep one cluster (in the clusterer's order, which a whole build takes
 * too) and raster its link 1, which blocks whole alpha slices. */
static void keep_cluster(void *ctx, const int32_t *members, int m)
{
    struct keep_ctx *k = (struct keep_ctx *)ctx;
    struct qrt_lazy_clusters *c = &k->pl->open.lazy.clusters;
    struct qrt_cluster_geom *g;
    int j;
    if (!k->ok || m < 1)
        return;
    if (m > QRT_CLUSTER_MAX || k->pl->lazy_clusters >= QRT_LAZY_MAX_CLUSTERS ||
        k->members + m > QRT_LAZY_MAX_POINTS) {
        k->ok = 0;
        return;
    }
    g = &c->geom[k->pl->lazy_clusters++];
    qrt_raster_cluster_prepare(k->r, (const float(*)[3])k->pl->points.xyz,
                               members, m, g, c->member_rho + k->members);
    g->first = (int32_t)k->members;
    for (j = 0; j < m; j++)
        c->members[k->members++] = members[j];
}

int qrt_lazy_begin(struct qrt_planner *pl, struct qrt_raster *r)
{
    struct keep_ctx k;
    double cell;
    int w;
    pl->lazy = 0;
    pl->lazy_kept = 0;
    pl->lazy_clusters = 0;
    for (w = 0; w < QRT_ROW_SET_WORDS; w++)
        pl->rows_ready[w] = 0;
    /* the clustering scratch of a whole build's part 0 */
    if (qrt_cluster_scratch_len(pl->points.count) > QRT_MAX_NODES)
        return 0;
    k.pl = pl;
    k.r = r;
    k.members = 0;
    k.ok = 1;
    qrt_cluster_points((const float(*)[3])pl->points.xyz, pl->points.count,
                       QRT_CLUSTER_CELL_M, QRT_CLUSTER_MAX, pl->heap_pos,
                       keep_cluster, &k);
    cell = qrt_cluster_cell_for(pl->points.count, pl->lazy_clusters);
    if (k.ok && cell != QRT_CLUSTER_CELL_M) {
        /* a sparse cloud: the larger cubes a whole build takes too (link
         * 1's slabs, rastered while keeping, come out the same again) */
        pl->lazy_clusters = 0;
        k.members = 0;
        qrt_cluster_points((const float(*)[3])pl->points.xyz, pl->points.count,
                           cell, QRT_CLUSTER_MAX, pl->heap_pos, keep_cluster,
                           &k);
    }
    if (!k.ok)
        return 0;
    pl->lazy_raster = r;
    pl->lazy = 1;
    return 1;
}

static void mark_ready(struct qrt_planner *pl, int ia, int is)
{
    long bit = (long)ia * QRT_MAX_NS + is;
    pl->rows_ready[bit >> 6] |= 1ULL << (bit & 63);
}

/* Every kept cluster that may block alpha node ia, in order, on the rows
 * the raster is restricted to. */
static void raster_alpha(struct qrt_planner *pl, int ia)
{
    const struct qrt_lazy_clusters *c = &pl->open.lazy.clusters;
    const float(*pts)[3] = (const float(*)[3])pl->points.xyz;
    long i;
    for (i = 0; i < pl->lazy_clusters; i++) {
        const struct qrt_cluster_geom *g = &c->geom[i];
        if ((g->alpha[ia >> 6] >> (ia & 63)) & 1U)
            qrt_raster_cluster_at(pl->lazy_raster, pts, c->members + g->first,
                                  c->member_rho + g->first, g, ia);
    }
}

void qrt_lazy_build(struct qrt_planner *pl, int ia, int is)
{
    int n1 = pl->mask.lat.n[1], s0 = is - is % LAZY_BLOCK_ROWS, s1, s;
    s1 = s0 + LAZY_BLOCK_ROWS < n1 ? s0 + LAZY_BLOCK_ROWS : n1;
    qrt_raster_only_block(pl->lazy_raster, ia, s0, s1);
    raster_alpha(pl, ia);
    qrt_raster_only_block(pl->lazy_raster, -1, 0, 0);
    for (s = s0; s < s1; s++)
        mark_ready(pl, ia, s);
}

void qrt_lazy_build_rows(struct qrt_planner *pl, const uint64_t *rows)
{
    uint64_t todo[QRT_ROW_SET_WORDS];
    int w, ia;
    for (w = 0; w < QRT_ROW_SET_WORDS; w++)
        todo[w] = (rows ? rows[w] : ~0ULL) & ~pl->rows_ready[w];
    qrt_raster_only_rows(pl->lazy_raster, todo);
    for (ia = 0; ia < pl->mask.lat.n[0]; ia++)
        if (pl->lazy_raster->alpha_wanted[ia])
            raster_alpha(pl, ia);
    qrt_raster_only_rows(pl->lazy_raster, NULL);
    for (w = 0; w < QRT_ROW_SET_WORDS; w++)
        pl->rows_ready[w] |= todo[w];
}

void qrt_lazy_finish(struct qrt_planner *pl)
{
    if (!pl->lazy)
        return;
    qrt_lazy_build_rows(pl, NULL);
    pl->lazy = 0;
    pl->lazy_kept = 0; /* the heap takes the clusters' room */
}

int qrt_lazy_end(struct qrt_planner *pl)
{
    int whole = !pl->lazy;
    pl->lazy = 0;
    pl->lazy_raster = NULL;
    return whole;
}

void qrt_lazy_resume(struct qrt_planner *pl, struct qrt_raster *r)
{
    pl->lazy_raster = r;
    pl->lazy = 1;
    pl->lazy_kept = 0; /* until the caller keeps them again */
}
