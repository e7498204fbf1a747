/* T-space -> C-space conversion: writes the blocked cells of obstacle
 * points into the mask (paper blocks b-d, Eqs. 1-12). Internal. */
#ifndef QRT_CORE_RASTER_H
#define QRT_CORE_RASTER_H

#include <stdint.h>

#include "qrtplan/arm.h"
#include "qrtplan/lattice.h"
#include "qrtplan/planner.h"
#include "tuning.h"

/* One lattice axis, in radians. */
struct qrt_axis {
    double lo, hi, inv_g;
    int n, wraps;
};

struct qrt_raster {
    const struct qrt_arm *arm;
    struct qrt_mask *mask;
    double radius_m[3]; /* collision radius per link, margins included */
    double h;           /* half-width of a cell box, radians */
    double g;           /* grid, radians */
    double lo[3];       /* joint value of node 0, radians */
    double elbow_shift; /* bound on elbow travel inside a box, metres */
    struct qrt_axis axis[3];
    double elbow[QRT_MAX_NS][2];      /* elbow (u, z) at each sigma node */
    uint64_t full_row[QRT_ROW_WORDS]; /* every eta node of a row */
    double cos_h, sin_h;
    double alpha_cs[QRT_MAX_NA][2]; /* cos, sin of each alpha node */
    /* this raster writes only alpha nodes ia with ia % nparts == part, so
     * that parts can run at once on different cores */
    int part, nparts;
    /* the edges of link 3's sector on each psi node j = is + ie, which
     * spans psi_j +- 2h: the directions (cos, sin) of psi_j - 2h and of
     * psi_j + 2h, as floats (off by < 1e-7 rad, which sector_eps covers) */
    float psi_edge[QRT_MAX_NS + QRT_MAX_NE - 1][4];
    /* NULL, or the only rows to raster (bit ia * QRT_MAX_NS + is); other
     * rows may be left partly written */
    const uint64_t *only_rows;
    /* >= 0: the only rows to raster are (only_alpha, only_s0 .. only_s1 - 1) */
    int only_alpha, only_s0, only_s1;
    unsigned char alpha_wanted[QRT_MAX_NA]; /* with only_rows: any row */
    double sector_eps;
    int sector_ok;
};

/* Prepare to raster: clears the mask. radius_m: per-link collision radius
 * (link radius + margin + point inflation); cspace_margin_deg widens every
 * cell box (Eq. 12). The raster covers every alpha node. */
void qrt_raster_begin(struct qrt_raster *r, struct qrt_mask *mask,
                      const struct qrt_arm *arm, const double radius_m[3],
                      double cspace_margin_deg);

/* The same without clearing the mask, for part `part` of `nparts`: the
 * raster then writes only the alpha nodes ia with ia % nparts == part.
 * Every alpha node's rows evolve exactly as in a whole raster (each row is
 * written only by operations on its own alpha node, in the same order), so
 * the parts together give the same mask bit for bit. */
void qrt_raster_setup(struct qrt_raster *r, struct qrt_mask *mask,
                      const struct qrt_arm *arm, const double radius_m[3],
                      double cspace_margin_deg, int part, int nparts);

/* Raster from now on only the rows in rows (bit ia * QRT_MAX_NS + is),
 * which must stay valid while this raster is used: the others are not
 * computed, and may be left partly written. NULL: every row again. */
void qrt_raster_only_rows(struct qrt_raster *r, const uint64_t *rows);

/* Raster from now on only the rows (ia, s0 .. s1 - 1); the others are not
 * computed, and may be left partly written. */
void qrt_raster_only_block(struct qrt_raster *r, int ia, int s0, int s1);

/* Mark every node whose cell box holds a configuration that collides with
 * point p (metres). */
void qrt_raster_point(const struct qrt_raster *r, const double p[3]);

/* The same result as qrt_raster_point on each of the m points
 * entries members[i] of ax (m <= QRT_CLUSTER_MAX), with less work when they lie
 * close together: the cells blocked are a superset of every cell a member truly
 * blocks, and a subset of what rastering them one by one blocks. */
void qrt_raster_cluster(const struct qrt_raster *r,
                        const struct qrt_point_axes *ax, const int32_t *members,
                        int m);

/* qrt_raster_cluster in two steps, so that a cluster can be rastered one
 * alpha node at a time: _prepare rasters the members' link 1 and fills *g
 * (bounding ball, and the alpha nodes whose boxes it may touch) and
 * mrho[0 .. m-1] (each member's distance from the base axis); _at rasters
 * links 2 and 3 at alpha node ia. _prepare, then _at on every alpha node,
 * is qrt_raster_cluster. 1 <= m <= QRT_CLUSTER_MAX. */
void qrt_raster_cluster_prepare(const struct qrt_raster *r,
                                const struct qrt_point_axes *ax,
                                const int32_t *members, int m,
                                struct qrti_cluster_geom *g, double *mrho);
void qrt_raster_cluster_at(const struct qrt_raster *r,
                           const struct qrt_point_axes *ax,
                           const int32_t *members, const double *mrho,
                           const struct qrti_cluster_geom *g, int ia);

/* qrt_raster_cluster_at in steps, for rows built one at a time from views
 * kept between them (the same bits as qrt_raster_cluster_at on the same
 * rows):
 * - _view_make: the cluster at alpha node ia (the caller owns ia); rasters
 *   link 2, whose rows are blocked whole, for every row at once. Returns 0
 *   where no member can touch links 2 or 3.
 * - _view_row: link 3 on row is; returns 1 when the members must be asked
 *   about the open nodes in ask (those of the row the ball blocks).
 * - _member_discs: the m members' discs at ia (m <= QRT_CLUSTER_MAX).
 * - _view_members: asks them.
 *
 * Where r->sector_ok (every grid under 90 degrees), a link-3 bit is set
 * exactly when link 2 blocks the row, or some cluster's ball and one of
 * its members (a one-point cluster: the point) both meet the node by the
 * sector test: a function of the node and the clusters alone, in any order.
 * So one node can be asked without its row, and gets the bit a row build
 * gives it:
 * - _next_ball: the first of views[k .. n-1] whose ball meets node
 *   (is, ie) by the sector test, or n; row_views, if not NULL, has bit k
 *   set exactly for the views whose rows hold is (only those are read);
 * - _node_members: does one of the m members' discs? */
int qrt_raster_view_make(const struct qrt_raster *r,
                         const struct qrt_point_axes *ax,
                         const int32_t *members, const double *mrho,
                         const struct qrti_cluster_geom *g, int ia,
                         struct qrti_alpha_view *v);
int qrt_raster_view_row(const struct qrt_raster *r,
                        const struct qrti_alpha_view *v, int m, int ia, int is,
                        uint64_t ask[QRT_ROW_WORDS]);
void qrt_raster_member_discs(const struct qrt_raster *r,
                             const struct qrt_point_axes *ax,
                             const int32_t *members, const double *mrho, int m,
                             int ia, struct qrti_disc *md);
void qrt_raster_view_members(const struct qrt_raster *r, int ia, int is,
                             const uint64_t ask[QRT_ROW_WORDS],
                             const struct qrti_disc *md, int m);
long qrt_raster_next_ball(const struct qrt_raster *r,
                          const struct qrti_alpha_view *views,
                          const uint64_t *row_views, long k, long n, int is,
                          int ie);
int qrt_raster_node_members(const struct qrt_raster *r, int is, int ie,
                            const struct qrti_disc *md, int m);

#endif
