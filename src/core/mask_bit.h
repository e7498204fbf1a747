/* A node's bit in the mask, inline for the search's inner loop;
 * qrt_mask_blocked is the same question across a call. Internal. */
#ifndef QRT_CORE_MASK_BIT_H
#define QRT_CORE_MASK_BIT_H

#include "bits.h"
#include "qrtplan/lattice.h"

static inline int qrt_mask_bit(const struct qrt_mask *mask, const int ijk[3])
{
    return qrt_bit_test(mask->rows[ijk[0]][ijk[1]], ijk[2]);
}

#endif
