/* The point table as the reference reads it, for the C tests. */
#ifndef QRT_TEST_STORED_POINTS_H
#define QRT_TEST_STORED_POINTS_H

#include "qrtplan/points.h"

/* The first n entries of the table, as 3n doubles (x, y, z of each): the
 * floats the planner tests against, not the doubles it was given. */
static inline void stored_points(const struct qrt_points *pts, long n,
                                 double *xyz)
{
    long i;
    for (i = 0; i < n; i++) {
        xyz[3 * i] = pts->x[i];
        xyz[3 * i + 1] = pts->y[i];
        xyz[3 * i + 2] = pts->z[i];
    }
}

#endif
