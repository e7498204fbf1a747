/* Brute-force search for the smallest clearance inside a cell box, with the
 * reference arm: the corners, then random starts, each improved by a
 * pattern search over the 26 neighbour directions with a halving step. */
#ifndef QRT_TEST_BOX_SEARCH_H
#define QRT_TEST_BOX_SEARCH_H

#include "check.h"
#include "ref_arm.h"

static inline double clamp_to(double x, double lo, double hi)
{
    return x < lo ? lo : (x > hi ? hi : x);
}

/* Smallest clearance found in centre +- h (degrees); worst gets where. */
static inline double box_min_clearance(const double *pts, long n,
                                       const double radius[3],
                                       const double centre[3], double h,
                                       int starts, double min_step,
                                       double worst[3])
{
    double best = 1e30;
    int start, k, c;
    for (start = 0; start < starts; start++) {
        double q[3], step = h, val;
        for (k = 0; k < 3; k++)
            q[k] = centre[k] + (start < 8 ? ((start >> k) & 1 ? h : -h)
                                          : test_uniform(-h, h));
        val = ref_clearance(q, pts, n, radius);
        while (step > min_step) {
            int improved = 0;
            for (c = 0; c < 27; c++) {
                double t[3], v;
                if (c == 13)
                    continue;
                t[0] = clamp_to(q[0] + (c / 9 - 1) * step, centre[0] - h,
                                centre[0] + h);
                t[1] = clamp_to(q[1] + ((c / 3) % 3 - 1) * step, centre[1] - h,
                                centre[1] + h);
                t[2] = clamp_to(q[2] + (c % 3 - 1) * step, centre[2] - h,
                                centre[2] + h);
                v = ref_clearance(t, pts, n, radius);
                if (v < val) {
                    val = v;
                    q[0] = t[0];
                    q[1] = t[1];
                    q[2] = t[2];
                    improved = 1;
                }
            }
            if (!improved)
                step *= 0.5;
        }
        if (val < best) {
            best = val;
            for (k = 0; k < 3; k++)
                worst[k] = q[k];
        }
    }
    return best;
}

#endif
