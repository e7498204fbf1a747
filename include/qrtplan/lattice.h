/* The joint lattice and its bit-packed obstacle mask.
 *
 * Node (ia, is, ie) sits at joints (lo_a + ia*g, lo_s + is*g, lo_e + ie*g).
 * Its cell box is the node plus or minus h = g/2 + cspace_margin in every
 * joint. The mask marks a node blocked when any configuration in its cell
 * box collides (conservative raster, docs/spec.md section Lattice): every
 * straight move between two free 26-neighbours runs through their two boxes
 * only, so it is safe.
 */
#ifndef QRTPLAN_LATTICE_H
#define QRTPLAN_LATTICE_H

#include <stdint.h>

#include "qrtplan/arm.h"
#include "qrtplan/config.h"

#ifdef __cplusplus
extern "C" {
#endif

struct qrt_lattice {
    int n[3];        /* nodes along alpha, sigma, eta */
    int alpha_wraps; /* node n[0] is node 0 again */
    double grid_deg;
    double lo_deg[3]; /* joint value of node 0 on each axis */
};

/* 64-bit words of a set of mask rows (alpha, sigma): bit
 * ia * QRT_MAX_NS + is. */
#define QRT_ROW_SET_WORDS ((QRT_MAX_NA * QRT_MAX_NS + 63) / 64)

struct qrt_mask {
    struct qrt_lattice lat;
    /* bit ie of row (ia, is) set = node blocked */
    uint64_t rows[QRT_MAX_NA][QRT_MAX_NS][QRT_ROW_WORDS];
};

/* Lattice for an arm's limits at grid_deg. QRT_E_INVALID for a bad grid
 * (not finite, below QRT_GRID_DEG_MIN, or not dividing 360 when alpha
 * wraps), QRT_E_TOO_BIG when it has more nodes per axis than this build. */
int qrt_lattice_init(struct qrt_lattice *lat, const struct qrt_arm *arm,
                     double grid_deg);

long qrt_lattice_node_count(const struct qrt_lattice *lat);
long qrt_lattice_index(const struct qrt_lattice *lat, const int ijk[3]);
void qrt_lattice_coords(const struct qrt_lattice *lat, long index, int ijk[3]);
void qrt_lattice_joints(const struct qrt_lattice *lat, const int ijk[3],
                        double joints_deg[3]);

int qrt_mask_blocked(const struct qrt_mask *mask, const int ijk[3]);
int qrt_mask_blocked_index(const struct qrt_mask *mask, long index);
long qrt_mask_count_blocked(const struct qrt_mask *mask);

#ifdef __cplusplus
}
#endif
#endif
