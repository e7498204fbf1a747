/* The joint lattice and the bit-packed mask over it. */
#include "qrtplan/lattice.h"

#include <math.h>

#include "qrtplan/status.h"

#include "mask_bit.h"

static const int max_nodes[3] = {QRT_MAX_NA, QRT_MAX_NS, QRT_MAX_NE};

int qrt_lattice_init(struct qrt_lattice *lat, const struct qrt_arm *arm,
                     double grid_deg)
{
    int j;
    if (!isfinite(grid_deg) || grid_deg < (double)QRT_GRID_DEG_MIN ||
        grid_deg > 180.0)
        return QRT_E_INVALID;
    lat->grid_deg = grid_deg;
    lat->alpha_wraps = qrt_arm_alpha_wraps(arm);
    for (j = 0; j < 3; j++) {
        double span = arm->limit_deg[j][1] - arm->limit_deg[j][0];
        /* a tiny tolerance so that 220/5 counts as 44 cells, not 43.999 */
        double cells = floor(span / grid_deg + 1e-9);
        lat->lo_deg[j] = arm->limit_deg[j][0];
        if (j == 0 && lat->alpha_wraps) {
            if (fabs(cells * grid_deg - 360.0) > 1e-9)
                return QRT_E_INVALID;
            lat->n[j] = (int)cells;
        } else {
            lat->n[j] = (int)cells + 1;
        }
        if (cells + 1.0 > (double)max_nodes[j] + 1.0 ||
            lat->n[j] > max_nodes[j])
            return QRT_E_TOO_BIG;
    }
    return QRT_OK;
}

long qrt_lattice_node_count(const struct qrt_lattice *lat)
{
    return (long)lat->n[0] * lat->n[1] * lat->n[2];
}

long qrt_lattice_index(const struct qrt_lattice *lat, const int ijk[3])
{
    return ((long)ijk[0] * lat->n[1] + ijk[1]) * lat->n[2] + ijk[2];
}

void qrt_lattice_coords(const struct qrt_lattice *lat, long index, int ijk[3])
{
    /* in 32 bits (a lattice has under 2^31 nodes): one hardware division
     * each, where a 64-bit one is tens of cycles on x86-64 and a library
     * call on 32-bit ARM; the search asks this of every node it takes */
    uint32_t i = (uint32_t)index, ne = (uint32_t)lat->n[2],
             ns = (uint32_t)lat->n[1], row = i / ne;
    ijk[2] = (int)(i - row * ne);
    ijk[1] = (int)(row % ns);
    ijk[0] = (int)(row / ns);
}

void qrt_lattice_joints(const struct qrt_lattice *lat, const int ijk[3],
                        double joints_deg[3])
{
    int j;
    for (j = 0; j < 3; j++)
        joints_deg[j] = lat->lo_deg[j] + ijk[j] * lat->grid_deg;
}

int qrt_mask_blocked(const struct qrt_mask *mask, const int ijk[3])
{
    return qrt_mask_bit(mask, ijk);
}

int qrt_mask_blocked_index(const struct qrt_mask *mask, long index)
{
    int ijk[3];
    qrt_lattice_coords(&mask->lat, index, ijk);
    return qrt_mask_blocked(mask, ijk);
}

static int popcount64(uint64_t x)
{
    int n = 0;
    while (x) {
        x &= x - 1u;
        n++;
    }
    return n;
}

long qrt_mask_count_blocked(const struct qrt_mask *mask)
{
    long total = 0;
    int a, s, w;
    for (a = 0; a < mask->lat.n[0]; a++)
        for (s = 0; s < mask->lat.n[1]; s++)
            for (w = 0; w < QRT_ROW_WORDS; w++)
                total += popcount64(mask->rows[a][s][w]);
    return total;
}
