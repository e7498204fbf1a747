/* A path's certified clearance. Internal. */
#ifndef QRT_CORE_CLEARANCE_H
#define QRT_CORE_CLEARANCE_H

#include "qrtplan/arm.h"
#include "qrtplan/lattice.h"
#include "qrtplan/points.h"

/* A lower bound on the least clearance (distance minus radius, metres) of
 * the arm's own capsules (its links and its tool, at their radii, no
 * margin) to the table's points over the straight motions through the n
 * waypoints (alpha the short way where the lattice wraps), the points'
 * inflation subtracted. It is within QRT_CERTIFY_SLACK_M / 2 of the least
 * clearance at the configurations it samples, so within that (plus the
 * inflation) of the true least clearance. A point ignored as out of
 * reach (pts->far_min2) counts as its distance from the base less how far
 * out the arm reaches along the path. collision_arm bounds how fast any
 * point of the arm moves (its last link reaches the tool's tip).
 * QRT_CLEARANCE_NONE_M when no point was given. block_box: scratch for
 * qrt_points_block_boxes. */
double qrt_path_clearance(const struct qrt_arm *arm,
                          const struct qrt_arm *collision_arm,
                          const struct qrt_points *pts,
                          const struct qrt_lattice *lat, float (*block_box)[6],
                          const double (*wp_deg)[3], int n);

#endif
