/* Mask rows built as they are read (see lazy.h). */
#include "lazy.h"

#include "bits.h"
#include "cluster.h"
#include "raster.h"
#include "tuning.h"

/* Most bytes the views and discs may take: the whole table, which tests
 * (test_plan_now_*) shrink to take the ways out when they do not fit. */
#ifndef QRT_LAZY_VIEW_BYTES
#define QRT_LAZY_VIEW_BYTES QRTI_LAZY_TABLE_BYTES
#endif

/* The table's bytes after the clusters. */
static long clusters_end(const struct qrt_planner *pl)
{
    return pl->lazy_clusters * (long)sizeof(struct qrti_cluster_geom);
}

/* Forget every view and disc kept (the table's bytes after the clusters
 * and their lists are free again). */
static void forget_views(struct qrt_planner *pl)
{
    int ia;
    pl->lazy_views_top = pl->lazy_lists_end;
    for (ia = 0; ia < QRT_MAX_NA; ia++) {
        pl->lazy_alpha_first[ia] = -1;
        pl->lazy_alpha_count[ia] = 0;
        pl->lazy_alpha_index[ia] = -1;
    }
}

/* Room for n items of size bytes after lazy_views_top: the first one's
 * index (the top moves past them), or -1. */
static long table_take(struct qrt_planner *pl, long n, long size)
{
    long first = (pl->lazy_views_top + size - 1) / size;
    long end = clusters_end(pl) + QRT_LAZY_VIEW_BYTES;
    if (end > QRTI_LAZY_TABLE_BYTES)
        end = QRTI_LAZY_TABLE_BYTES;
    if ((first + n) * size > end)
        return -1;
    pl->lazy_views_top = (first + n) * size;
    return first;
}

struct keep_ctx {
    struct qrt_planner *pl;
    struct qrt_point_axes ax;
    const struct qrt_raster *r;
    long members;
    int ok;
};

/* Keep one cluster (in the clusterer's order, which a whole build takes
 * too) and raster its link 1, which blocks whole alpha slices. */
static void keep_cluster(void *ctx, const int32_t *members, int m)
{
    struct keep_ctx *k = (struct keep_ctx *)ctx;
    struct qrti_lazy_clusters *c = &k->pl->open.lazy.clusters;
    struct qrti_cluster_geom *g;
    int j;
    if (!k->ok || m < 1)
        return;
    if (m > QRT_CLUSTER_MAX || k->pl->lazy_clusters >= QRTI_LAZY_MAX_CLUSTERS ||
        k->members + m > QRTI_LAZY_MAX_POINTS) {
        k->ok = 0;
        return;
    }
    g = &c->t.geom[k->pl->lazy_clusters++];
    qrt_raster_cluster_prepare(k->r, &k->ax, members, m, g,
                               c->member_rho + k->members);
    g->first = (int32_t)k->members;
    for (j = 0; j < m; j++)
        c->members[k->members++] = members[j];
}

static void clear_known(struct qrt_planner *pl)
{
    long w, words = (qrt_lattice_node_count(&pl->mask.lat) + 63) / 64;
    for (w = 0; w < words; w++)
        pl->open.lazy.clusters.known[w] = 0;
}

/* List each alpha node's kept clusters, in cluster order, right after
 * the clusters, so that its views are made from them alone; where the
 * lists do not fit, every cluster is asked instead (lazy_lists 0). */
static void make_alpha_lists(struct qrt_planner *pl)
{
    struct qrti_lazy_clusters *c = &pl->open.lazy.clusters;
    long i, at = (clusters_end(pl) + 3) / 4, total = 0, end;
    int ia, w;
    pl->lazy_lists = 0;
    pl->lazy_lists_end = clusters_end(pl);
    for (ia = 0; ia < QRT_MAX_NA; ia++)
        pl->lazy_alpha_clusters[ia] = 0;
    for (i = 0; i < pl->lazy_clusters; i++)
        for (w = 0; w < QRTI_ALPHA_WORDS; w++) {
            uint64_t bits = c->t.geom[i].alpha[w];
            for (; bits; bits &= bits - 1U)
                pl->lazy_alpha_clusters[(w << 6) + qrt_lowest_bit(bits)]++;
        }
    for (ia = 0; ia < QRT_MAX_NA; ia++) {
        pl->lazy_alpha_list[ia] = (int32_t)(at + total);
        total += pl->lazy_alpha_clusters[ia];
        pl->lazy_alpha_count[ia] = 0; /* a cursor until forget_views */
    }
    end = (at + total) * (long)sizeof(int32_t);
    if (end > clusters_end(pl) + QRT_LAZY_VIEW_BYTES ||
        end > QRTI_LAZY_TABLE_BYTES)
        return;
    for (i = 0; i < pl->lazy_clusters; i++)
        for (w = 0; w < QRTI_ALPHA_WORDS; w++) {
            uint64_t bits = c->t.geom[i].alpha[w];
            for (; bits; bits &= bits - 1U) {
                ia = (w << 6) + qrt_lowest_bit(bits);
                c->t.list[pl->lazy_alpha_list[ia] +
                          pl->lazy_alpha_count[ia]++] = (int32_t)i;
            }
        }
    pl->lazy_lists = 1;
    pl->lazy_lists_end = end;
}

int qrt_lazy_begin(struct qrt_planner *pl, struct qrt_raster *r)
{
    struct keep_ctx k;
    double cell;
    int w;
    pl->lazy_raster = NULL;
    pl->lazy_clusters = 0;
    for (w = 0; w < QRT_ROW_SET_WORDS; w++)
        pl->rows_ready[w] = 0;
    clear_known(pl);
    /* the clustering scratch of a whole build's part 0 */
    if (qrt_cluster_scratch_len(pl->points.count) > QRT_MAX_NODES)
        return 0;
    k.pl = pl;
    k.ax = qrt_points_axes(&pl->points);
    k.r = r;
    k.members = 0;
    k.ok = 1;
    qrt_cluster_points(&k.ax, pl->points.count, QRT_CLUSTER_CELL_M,
                       QRT_CLUSTER_MAX, pl->heap_pos, keep_cluster, &k);
    cell = qrt_cluster_cell_for(pl->points.count, pl->lazy_clusters);
    if (k.ok && cell != QRT_CLUSTER_CELL_M) {
        /* a sparse cloud: the larger cubes a whole build takes too (link
         * 1's slabs, rastered while keeping, come out the same again) */
        pl->lazy_clusters = 0;
        k.members = 0;
        qrt_cluster_points(&k.ax, pl->points.count, cell, QRT_CLUSTER_MAX,
                           pl->heap_pos, keep_cluster, &k);
    }
    if (!k.ok)
        return 0;
    make_alpha_lists(pl);
    forget_views(pl);
    pl->lazy_forgets = pl->lazy_unviewed_rows = pl->lazy_unkept_discs = 0;
    pl->lazy_nodes_asked = 0;
    pl->lazy_raster = r;
    pl->mask_state = QRT_MASK_PARTIAL;
    return 1;
}

static void mark_ready(struct qrt_planner *pl, int ia, int is)
{
    long bit = (long)ia * QRT_MAX_NS + is;
    qrt_bit_set(pl->rows_ready, bit);
}

/* The kept clusters' views of alpha node ia, made now if they are not kept
 * (forgetting all the others when the free bytes are too few). Returns the
 * first view's index, or -1 when even all the free bytes cannot hold them. */
static long alpha_views(struct qrt_planner *pl, int ia)
{
    const long size = (long)sizeof(struct qrti_alpha_view);
    struct qrti_lazy_clusters *c = &pl->open.lazy.clusters;
    const struct qrt_point_axes ax = qrt_points_axes(&pl->points);
    long i, n = 0, first, k = 0, e, count;
    if (pl->lazy_alpha_first[ia] >= 0)
        return pl->lazy_alpha_first[ia];
    if (pl->lazy_lists)
        n = pl->lazy_alpha_clusters[ia];
    else
        for (i = 0; i < pl->lazy_clusters; i++)
            n += qrt_bit_test(c->t.geom[i].alpha, ia);
    first = table_take(pl, n, size);
    if (first < 0) {
        forget_views(pl);
        pl->lazy_forgets++;
        first = table_take(pl, n, size);
    }
    if (first < 0) {
        pl->lazy_unviewed_rows++;
        return -1;
    }
    count = pl->lazy_lists ? n : pl->lazy_clusters;
    for (e = 0; e < count; e++) {
        const struct qrti_cluster_geom *g;
        struct qrti_alpha_view *v = &c->t.view[first + k];
        i = pl->lazy_lists ? c->t.list[pl->lazy_alpha_list[ia] + e] : e;
        g = &c->t.geom[i];
        if (qrt_bit_test(g->alpha, ia) &&
            qrt_raster_view_make(pl->lazy_raster, &ax, c->members + g->first,
                                 c->member_rho + g->first, g, ia, v)) {
            v->cluster = (int32_t)i;
            v->members_at = -1;
            k++;
        }
    }
    pl->lazy_views_top = (first + k) * size; /* the rest is free again */
    pl->lazy_alpha_first[ia] = (int32_t)first;
    pl->lazy_alpha_count[ia] = (int32_t)k;
    return first;
}

/* The members' discs of view v: kept from the first time they are asked
 * for, while the free bytes last; else made into scratch each time. */
static const struct qrti_disc *member_discs(struct qrt_planner *pl, int ia,
                                            struct qrti_alpha_view *v,
                                            struct qrti_disc *scratch)
{
    struct qrti_lazy_clusters *c = &pl->open.lazy.clusters;
    const struct qrti_cluster_geom *g = &c->t.geom[v->cluster];
    const struct qrt_point_axes ax = qrt_points_axes(&pl->points);
    struct qrti_disc *md = scratch;
    long at;
    if (v->members_at >= 0)
        return &c->t.disc[v->members_at];
    at = table_take(pl, g->m, (long)sizeof(struct qrti_disc));
    if (at >= 0) {
        v->members_at = (int32_t)at;
        md = &c->t.disc[at];
    } else {
        pl->lazy_unkept_discs++;
    }
    qrt_raster_member_discs(pl->lazy_raster, &ax, c->members + g->first,
                            c->member_rho + g->first, g->m, ia, md);
    return md;
}

/* Row (ia, is) from every kept cluster that may block alpha node ia, in
 * order, through their kept views. */
void qrt_lazy_build(struct qrt_planner *pl, int ia, int is)
{
    struct qrti_lazy_clusters *c = &pl->open.lazy.clusters;
    struct qrti_disc scratch[QRT_CLUSTER_MAX];
    long first, k;
    qrt_raster_only_block(pl->lazy_raster, ia, is, is + 1);
    first = alpha_views(pl, ia);
    if (first < 0) { /* no room for the views: each cluster from scratch */
        const struct qrt_point_axes ax = qrt_points_axes(&pl->points);
        for (k = 0; k < pl->lazy_clusters; k++) {
            const struct qrti_cluster_geom *g = &c->t.geom[k];
            qrt_raster_cluster_at(pl->lazy_raster, &ax, c->members + g->first,
                                  c->member_rho + g->first, g, ia);
        }
    }
    for (k = 0; first >= 0 && k < pl->lazy_alpha_count[ia]; k++) {
        struct qrti_alpha_view *v = &c->t.view[first + k];
        uint64_t ask[QRT_ROW_WORDS];
        int m;
        if (!qrt_bit_test(v->rows, is))
            continue; /* (asked again inside; most views miss the row) */
        m = c->t.geom[v->cluster].m;
        if (qrt_raster_view_row(pl->lazy_raster, v, m, ia, is, ask))
            qrt_raster_view_members(pl->lazy_raster, ia, is, ask,
                                    member_discs(pl, ia, v, scratch), m);
    }
    qrt_raster_only_block(pl->lazy_raster, -1, 0, 0);
    mark_ready(pl, ia, is);
}

/* The bits of alpha node ia's views that reach sigma row is, from its
 * index (see lazy_alpha_index), made once enough single-node queries fell
 * on it that reading only the views of a node's row saves more than
 * the index costs; NULL until then, or when it does not fit (the views are
 * never forgotten for it: the caller holds their place). */
static const uint64_t *row_views_of(struct qrt_planner *pl, long first, int ia,
                                    int is)
{
    struct qrti_lazy_clusters *c = &pl->open.lazy.clusters;
    int32_t *at = &pl->lazy_alpha_index[ia];
    long n = pl->lazy_alpha_count[ia], words = (n + 63) / 64, k, w, index;
    int ns = pl->mask.lat.n[1];
    if (*at >= 0)
        return &c->t.row_views[*at + is * words];
    if (*at == QRTI_LAZY_NO_INDEX || --*at > -1 - QRT_LAZY_INDEX_AFTER)
        return NULL;
    index = table_take(pl, ns * words, (long)sizeof(uint64_t));
    if (index < 0) {
        *at = QRTI_LAZY_NO_INDEX;
        return NULL;
    }
    for (k = 0; k < ns * words; k++)
        c->t.row_views[index + k] = 0;
    for (k = 0; k < n; k++)
        for (w = 0; w < QRTI_SIGMA_WORDS; w++) {
            uint64_t rows = c->t.view[first + k].rows[w];
            for (; rows; rows &= rows - 1U) {
                long row = (w << 6) + qrt_lowest_bit(rows);
                if (row < ns) /* always (the axis's ranges); the writes
                                stay in the index whatever a view says */
                    qrt_bit_set(&c->t.row_views[index + row * words], k);
            }
        }
    *at = (int32_t)index;
    return &c->t.row_views[index + is * words];
}

/* Node (ia, is, ie) from the kept views of alpha node ia: blocked when
 * a view's ball and then one of its members (a one-point cluster: the
 * point) meet it; the first that does ends the question. (Not static,
 * so that its discs' scratch is not on the stack under qrt_lazy_build.) */
int qrt_lazy_node_from_views(struct qrt_planner *pl, long first, int ia, int is,
                             int ie)
{
    struct qrti_lazy_clusters *c = &pl->open.lazy.clusters;
    struct qrti_disc scratch[QRT_CLUSTER_MAX];
    const struct qrti_alpha_view *views = &c->t.view[first];
    long k, n = pl->lazy_alpha_count[ia];
    const uint64_t *row = row_views_of(pl, first, ia, is);
    for (k = qrt_raster_next_ball(pl->lazy_raster, views, row, 0, n, is, ie);
         k < n; k = qrt_raster_next_ball(pl->lazy_raster, views, row, k + 1, n,
                                         is, ie)) {
        struct qrti_alpha_view *v = &c->t.view[first + k];
        int m = c->t.geom[v->cluster].m;
        if (m == 1 ||
            qrt_raster_node_members(pl->lazy_raster, is, ie,
                                    member_discs(pl, ia, v, scratch), m))
            return 1;
    }
    return 0;
}

int qrt_lazy_node_blocked(struct qrt_planner *pl, const int ijk[3])
{
    uint64_t *row = pl->mask.rows[ijk[0]][ijk[1]];
    long first;
    if (qrt_lazy_known(pl, ijk))
        return qrt_bit_test(row, ijk[2]);
    first = pl->lazy_raster->sector_ok ? alpha_views(pl, ijk[0]) : -1;
    if (first < 0) { /* the row, as qrt_lazy_build makes it */
        qrt_lazy_build(pl, ijk[0], ijk[1]);
        return qrt_bit_test(row, ijk[2]);
    }
    /* link 1 and link 2 block whole rows, rastered before this */
    if (!qrt_bit_test(row, ijk[2]) &&
        qrt_lazy_node_from_views(pl, first, ijk[0], ijk[1], ijk[2]))
        qrt_bit_set(row, ijk[2]);
    qrt_bit_set(pl->open.lazy.clusters.known, qrt_lazy_known_bit(pl, ijk));
    pl->lazy_nodes_asked++;
    return qrt_bit_test(row, ijk[2]);
}

void qrt_lazy_build_rows(struct qrt_planner *pl, const uint64_t *rows)
{
    int ia, is;
    for (ia = 0; ia < pl->mask.lat.n[0]; ia++)
        for (is = 0; is < pl->mask.lat.n[1]; is++) {
            long bit = (long)ia * QRT_MAX_NS + is;
            if ((!rows || qrt_bit_test(rows, bit)) &&
                !qrt_lazy_ready(pl, ia, is))
                qrt_lazy_build(pl, ia, is);
        }
}

void qrt_lazy_finish(struct qrt_planner *pl)
{
    if (!qrt_lazy_building(pl))
        return;
    qrt_lazy_build_rows(pl, NULL);
    pl->lazy_raster = NULL;
    pl->mask_state = QRT_MASK_WHOLE; /* the heap takes the clusters' room */
}

int qrt_lazy_end(struct qrt_planner *pl)
{
    pl->lazy_raster = NULL;
    return pl->mask_state == QRT_MASK_WHOLE;
}

void qrt_lazy_renumber(struct qrt_planner *pl, const int32_t *new_place)
{
    long c;
    if (pl->mask_state != QRT_MASK_PARTIAL) /* no cluster is kept */
        return;
    for (c = 0; c < pl->lazy_clusters; c++) {
        const struct qrti_cluster_geom *g = &pl->open.lazy.clusters.t.geom[c];
        int32_t j;
        for (j = g->first; j < g->first + g->m; j++)
            pl->open.lazy.clusters.members[j] =
                new_place[pl->open.lazy.clusters.members[j]];
    }
}

void qrt_lazy_resume(struct qrt_planner *pl, struct qrt_raster *r)
{
    pl->lazy_raster = r;
}
