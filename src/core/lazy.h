/* Mask rows built as they are read, for qrt_planner_plan_now. Internal.
 *
 * The points are clustered once (qrt_lazy_begin) and the clusters kept in
 * the tail of the heap array; a row is built the first time it is read,
 * from every cluster that may block its alpha node, in the order a whole
 * build takes them. A row's bits depend only on the operations on that
 * row, in that order (raster.h), so each row comes out bit for bit as
 * qrt_planner_build_mask makes it. What a cluster looks like at an alpha
 * node (its view: the ball's disc, the rows link 3 may reach, its
 * members' discs once asked for) is kept in the table's free bytes for the
 * next row on that node; when they run out, the views are forgotten and
 * made again as needed. */
#ifndef QRT_CORE_LAZY_H
#define QRT_CORE_LAZY_H

#include "bits.h"
#include "qrtplan/planner.h"

/* Cluster the points into pl->open.lazy and keep them there, with r (set
 * up for the cleared mask, owned by the caller until qrt_lazy_end).
 * Returns 1, rows now built as read and the mask partial, or 0 (too many
 * clusters, or no scratch for clustering): then build the whole mask
 * instead. */
int qrt_lazy_begin(struct qrt_planner *pl, struct qrt_raster *r);

/* Build row (ia, is). */
void qrt_lazy_build(struct qrt_planner *pl, int ia, int is);

/* Is the current call building rows as it reads them (between
 * qrt_lazy_begin or qrt_lazy_resume and qrt_lazy_end or qrt_lazy_finish)? */
static inline int qrt_lazy_building(const struct qrt_planner *pl)
{
    return pl->lazy_raster != NULL;
}

/* Is row (ia, is) there to read (built, or no rows are built as read)? */
static inline int qrt_lazy_ready(const struct qrt_planner *pl, int ia, int is)
{
    long bit = (long)ia * QRT_MAX_NS + is;
    return !qrt_lazy_building(pl) || qrt_bit_test(pl->rows_ready, bit);
}

/* Row (ia, is) built, if rows are being built as they are read. */
static inline void qrt_lazy_need(struct qrt_planner *pl, int ia, int is)
{
    if (!qrt_lazy_ready(pl, ia, is))
        qrt_lazy_build(pl, ia, is);
}

/* Is node ijk (inside the lattice) blocked? Where rows are built as they
 * are read, a node of a row not built yet is a single-node query when the
 * sector test holds (the bit a row build gives it, raster.h), else its row is
 * built. */
int qrt_lazy_node_blocked(struct qrt_planner *pl, const int ijk[3]);

/* qrt_lazy_node_blocked's question of alpha node ia's views (from view
 * first), for a node whose bit is not set yet. */
int qrt_lazy_node_from_views(struct qrt_planner *pl, long first, int ia, int is,
                             int ie);

/* Bit of node ijk in the kept clusters' known set. */
static inline long qrt_lazy_known_bit(const struct qrt_planner *pl,
                                      const int ijk[3])
{
    const int *n = pl->mask.lat.n;
    return ((long)ijk[0] * n[1] + ijk[1]) * n[2] + ijk[2];
}

/* Is node ijk's bit there to read (its row built, a single-node query set it,
 * or the mask is whole)? */
static inline int qrt_lazy_known(const struct qrt_planner *pl, const int ijk[3])
{
    long bit;
    if (qrt_lazy_ready(pl, ijk[0], ijk[1]))
        return 1;
    bit = qrt_lazy_known_bit(pl, ijk);
    return qrt_bit_test(pl->open.lazy.clusters.known, bit);
}

/* Build the rows in rows (bit ia * QRT_MAX_NS + is; NULL: every row) that
 * are not built yet. */
void qrt_lazy_build_rows(struct qrt_planner *pl, const uint64_t *rows);

/* Build every row not built yet and give the clusters up (the heap may
 * then use the whole array). The mask is whole afterwards
 * (QRT_MASK_WHOLE). */
void qrt_lazy_finish(struct qrt_planner *pl);

/* Stop building rows; returns whether the mask is whole. Otherwise the
 * clusters and the rows built stay kept (QRT_MASK_PARTIAL), so that a
 * later qrt_lazy_resume takes them up again. */
int qrt_lazy_end(struct qrt_planner *pl);

/* The table's entries were moved (order.h): new_place[i] is where the
 * entry that was at i is now. The kept clusters name their members by
 * place, so they follow. */
void qrt_lazy_renumber(struct qrt_planner *pl, const int32_t *new_place);

/* Build rows as they are read again, from the clusters and rows kept by
 * the last qrt_lazy_end, with r set up as for qrt_lazy_begin. */
void qrt_lazy_resume(struct qrt_planner *pl, struct qrt_raster *r);

#endif
