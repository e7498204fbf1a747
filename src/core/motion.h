/* Certifying straight joint-space motions. Internal. */
#ifndef QRT_CORE_MOTION_H
#define QRT_CORE_MOTION_H

#include <stdint.h>

#include "qrtplan/arm.h"
#include "qrtplan/lattice.h"
#include "qrtplan/points.h"
#include "tuning.h"

/* Joint step from a to b in degrees: alpha the short way round, in
 * (-180, 180], when the lattice wraps (docs/spec.md section Guarantee). */
void qrt_motion_delta(const struct qrt_lattice *lat, const double a_deg[3],
                      const double b_deg[3], double d_deg[3]);

/* How fast (metres per unit of the motion's parameter) any point of link k
 * can move on a straight motion whose joints change by d_deg: each joint's
 * rate times the farthest link k reaches from that joint's axis. */
void qrt_motion_link_speeds(const struct qrt_arm *arm, const double d_deg[3],
                            double speed[3]);

/* 1 if every configuration on the straight motion a -> b lies in the cell
 * of a free lattice node (so collides with nothing), else 0. */
int qrt_motion_free_on_mask(const struct qrt_mask *mask, const double a_deg[3],
                            const double b_deg[3]);

/* qrt_motion_free_on_mask, and where it fails, *t_hit: the motion's
 * parameter (0..1) in the middle of the first cell that is blocked or
 * outside the lattice. */
int qrt_motion_free_on_mask_hit(const struct qrt_mask *mask,
                                const double a_deg[3], const double b_deg[3],
                                double *t_hit);

/* Does the configuration at parameter t of the motion a -> b (alpha the
 * short way) collide with the points (clearance <= 1e-7 m)? */
int qrt_motion_collides_at(const struct qrt_arm *arm, const double radius_m[3],
                           const struct qrt_points *pts,
                           const struct qrt_lattice *lat, const double a_deg[3],
                           const double b_deg[3], double t);

/* Is node ijk blocked? Asked of a mask whose nodes are found as they are
 * read. */
typedef int (*qrt_node_blocked)(void *ctx, const int ijk[3]);

/* qrt_motion_free_on_mask on a mask whose nodes are found as they are
 * read: blocked(ctx, ijk) answers for each node instead of the mask. */
int qrt_motion_free_asking(const struct qrt_mask *mask,
                           qrt_node_blocked blocked, void *ctx,
                           const double a_deg[3], const double b_deg[3]);

/* Mark in rows (bit ia * QRT_MAX_NS + is) every mask row that
 * qrt_motion_free_on_mask(mask, a, b) looks at. */
void qrt_motion_mark_rows(const struct qrt_mask *mask, const double a_deg[3],
                          const double b_deg[3], uint64_t *rows);

/* Smallest clearance (distance minus collision radius, metres) between the
 * arm at q_deg and the points; a large value when there are none; where
 * the arm collides, some value <= 0. */
double qrt_clearance(const struct qrt_arm *arm, const double radius_m[3],
                     const struct qrt_points *pts, const double q_deg[3]);

/* Capsules in a chain: capsule k joins p[k] and p[k + 1] (the three links,
 * and the tool after them). */
#define QRT_CHAIN_MAX 4

/* The arm's own capsules at q_deg as a chain (its three links, then its
 * tool when it has one): their ends p[0..n] and radii radius_m[0..n-1],
 * each the capsule's radius plus extra_m. Returns n (3 or 4). */
int qrt_arm_capsules(const struct qrt_arm *arm, const double q_deg[3],
                     double extra_m, double (*p)[3], double *radius_m);

/* min(clearance, cap) of the chain of n <= QRT_CHAIN_MAX capsules p[0..n]
 * with radii radius_m[0..n-1] against the points (distance minus radius,
 * metres; points farther than cap from every capsule are skipped); where
 * a capsule collides, some value <= 0. block_box: NULL, or the table's
 * qrt_points_block_boxes. */
double qrt_chain_clearance_capped(const double (*p)[3], const double *radius_m,
                                  int n, const struct qrt_points *pts,
                                  const float (*block_box)[6], double cap);

/* The box of each block of QRT_CLEARANCE_BLOCK entries of the table (its
 * least x, y, z, then its greatest, as stored), then the box of each group
 * of QRT_CLEARANCE_GROUP blocks, for qrt_chain_clearance_capped to pass
 * over a block or a group that lies wholly out of its reach: B =
 * (count + QRT_CLEARANCE_BLOCK - 1) / QRT_CLEARANCE_BLOCK boxes, then
 * (B + QRT_CLEARANCE_GROUP - 1) / QRT_CLEARANCE_GROUP. */
void qrt_points_block_boxes(const struct qrt_points *pts,
                            float (*block_box)[6]);

/* min(clearance, cap) where the arm is clear of every point, cheaper than
 * qrt_clearance since points farther than cap from the arm are skipped;
 * where it collides, some value <= 0 (the search stops at the first
 * colliding point). */
double qrt_clearance_capped(const struct qrt_arm *arm, const double radius_m[3],
                            const struct qrt_points *pts, const double q_deg[3],
                            double cap);

/* 1 if the motion a -> b is proved free against the points themselves by
 * conservative advancement (each step shorter than the clearance divided by
 * how fast any point of the arm can move), else 0 (also when it would take
 * more than max_steps steps). After witness_after steps, samples of the
 * motion are searched for a colliding one, which ends a blocked motion's
 * crawl towards the contact (the answer is the same): QRT_WITNESS_AFTER
 * suits motions that are often free (connections advancement proves in a
 * step or two), 0 motions known to be blocked nearly always. block_box:
 * NULL, or the table's qrt_points_block_boxes (the same answer, sooner
 * where whole blocks lie far from the arm). */
int qrt_motion_free_exact(const struct qrt_arm *arm, const double radius_m[3],
                          const struct qrt_points *pts,
                          const float (*block_box)[6],
                          const struct qrt_lattice *lat, const double a_deg[3],
                          const double b_deg[3], int max_steps,
                          int witness_after);

#endif
