/* The lattice's neighbour relation as the tests' reference Dijkstras walk
 * it, written here rather than taken from the core. */
#ifndef QRT_TEST_REF_LATTICE_H
#define QRT_TEST_REF_LATTICE_H

#include "qrtplan/lattice.h"

/* Index of node (a, s, e), alpha wrapping where the lattice wraps; -1
 * outside the lattice. */
static long wrap_index(const struct qrt_lattice *lat, int a, int s, int e)
{
    int ijk[3];
    if (lat->alpha_wraps)
        a = (a + lat->n[0]) % lat->n[0];
    if (a < 0 || a >= lat->n[0] || s < 0 || s >= lat->n[1] || e < 0 ||
        e >= lat->n[2])
        return -1;
    ijk[0] = a;
    ijk[1] = s;
    ijk[2] = e;
    return qrt_lattice_index(lat, ijk);
}

#endif
