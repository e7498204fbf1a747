/* Proving one straight joint-space motion free against the points
 * themselves, in one pass over them and with nothing built first: the
 * first thing a plan in open space asks. Internal. */
#ifndef QRT_CORE_SWEEP_H
#define QRT_CORE_SWEEP_H

#include "qrtplan/arm.h"
#include "qrtplan/lattice.h"
#include "qrtplan/planner.h"
#include "qrtplan/points.h"

/* 1 if every configuration on the straight motion a -> b (alpha the short
 * way when lat's alpha wraps) keeps every point at least radius_m[k] from link
 * k, so collides with nothing; 0 if that is not proved: the motion collides, or
 * passes too close to some point for this proof (then the mask decides), or the
 * proof would take more than a few steps a point.
 *
 * How: a point can come near the arm only while alpha is within a window of
 * its bearing (the arm lies in a vertical plane through the base axis), and
 * inside that window it is advanced conservatively along the motion from
 * stored configurations of it (each link's clearance divided by how fast
 * any of its points can move). Points near the sweep are taken in the
 * table's order as runs of 8, each first as one ball that holds them (the
 * links' radii grown by the ball's), then as two half runs, then alone: a
 * scan lists its points along surfaces, so a run is mostly a small patch.
 * poses is scratch for QRTI_SWEEP_POSES. */
int qrt_sweep_free(const struct qrt_arm *arm, const double radius_m[3],
                   const struct qrt_points *pts, const struct qrt_lattice *lat,
                   const double a_deg[3], const double b_deg[3],
                   struct qrti_sweep_pose *poses);

#endif
