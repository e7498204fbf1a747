/* The sampled fallback: a path off the lattice when the lattice has none.
 * Internal.
 *
 * The lattice's conservative cells close passages narrower than a cell's
 * sweep (docs/spec.md section Lattice). Where its search finds no path,
 * two trees of configurations grow from the start and the goal towards
 * random configurations and towards each other (RRT-Connect), each edge a
 * straight motion proved free against the points themselves by
 * conservative advancement, the same proof that joins a start to the
 * lattice. The random draws come from a generator with a fixed seed, so
 * the answer is a function of the inputs alone. */
#ifndef QRT_CORE_SAMPLED_H
#define QRT_CORE_SAMPLED_H

#include <stdint.h>

#include "qrtplan/arm.h"
#include "qrtplan/lattice.h"
#include "qrtplan/planner.h"
#include "qrtplan/points.h"

/* What the trees are proved against, and the caller's scratch. */
struct qrt_sampled_space {
    const struct qrt_arm *arm; /* the collision arm (and the limits) */
    double radius_m[3];        /* its collision radii */
    const struct qrt_points *pts;
    const float (*block_box)[6];    /* the table's qrt_points_block_boxes */
    const struct qrt_lattice *lat;  /* joint limits and alpha's wrap */
    struct qrti_sampled_node *node; /* room for max_nodes */
    int32_t *path;                  /* room for max_nodes */
    int32_t max_nodes;
};

/* Grow the trees between qs and qg (both free) for at most draws random
 * configurations, or until the node table is full. On success returns the
 * number of configurations of the path, start to goal, as indices into
 * space->node listed in space->path (each straight motion between
 * consecutive ones proved free); 0 when none was found. *nodes_used: the
 * tree nodes made. */
int32_t qrt_sampled_connect(const struct qrt_sampled_space *space,
                            const double qs[3], const double qg[3], long draws,
                            long *nodes_used);

/* Is the straight motion a -> b proved free in space (the edges' proof)? */
int qrt_sampled_motion_free(const struct qrt_sampled_space *space,
                            const double a[3], const double b[3]);

#endif
