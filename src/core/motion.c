/* Certifying straight joint-space motions against the mask or the points. */
#include "motion.h"

#include <math.h>

#include "geom.h"

void qrt_motion_delta(const struct qrt_lattice *lat, const double a_deg[3],
                      const double b_deg[3], double d_deg[3])
{
    int j;
    for (j = 0; j < 3; j++)
        d_deg[j] = b_deg[j] - a_deg[j];
    if (lat->alpha_wraps)
        d_deg[0] = qrt_wrap_deg(d_deg[0]);
}

/* Is the cell whose node is nearest to continuous lattice coordinates x
 * free? Outside the lattice counts as blocked. */
static int cell_free(const struct qrt_mask *mask, const double x[3])
{
    const struct qrt_lattice *lat = &mask->lat;
    int ijk[3], j;
    for (j = 0; j < 3; j++) {
        double k = floor(x[j] + 0.5);
        if (j == 0 && lat->alpha_wraps)
            k -= lat->n[0] * floor(k / lat->n[0]);
        if (k < 0.0 || k > (double)(lat->n[j] - 1))
            return 0;
        ijk[j] = (int)k;
    }
    return !qrt_mask_blocked(mask, ijk);
}

int qrt_motion_free_on_mask(const struct qrt_mask *mask, const double a_deg[3],
                            const double b_deg[3])
{
    const struct qrt_lattice *lat = &mask->lat;
    double x0[3], dx[3], d[3], next_t[3], step_t[3], t = 0.0;
    int j;

    qrt_motion_delta(lat, a_deg, b_deg, d);
    /* Walk the parameter t in [0, 1] from one cell boundary (node +- half a
     * grid step on some axis) to the next; between two boundaries the
     * motion stays in one cell, named by its midpoint. */
    for (j = 0; j < 3; j++) {
        x0[j] = (a_deg[j] - lat->lo_deg[j]) / lat->grid_deg;
        dx[j] = d[j] / lat->grid_deg;
        if (dx[j] == 0.0) {
            next_t[j] = 2.0;
            step_t[j] = 0.0;
            continue;
        }
        step_t[j] = 1.0 / fabs(dx[j]);
        {
            double first = dx[j] > 0.0 ? floor(x0[j] + 0.5) + 0.5
                                       : ceil(x0[j] - 0.5) - 0.5;
            next_t[j] = (first - x0[j]) / dx[j];
        }
    }
    for (;;) {
        double t_end = 1.0, mid[3];
        int axis = -1;
        for (j = 0; j < 3; j++)
            if (next_t[j] < t_end) {
                t_end = next_t[j];
                axis = j;
            }
        for (j = 0; j < 3; j++)
            mid[j] = x0[j] + 0.5 * (t + t_end) * dx[j];
        if (!cell_free(mask, mid))
            return 0;
        if (axis < 0)
            return 1;
        t = t_end;
        next_t[axis] += step_t[axis];
    }
}

double qrt_clearance(const struct qrt_arm *arm, const double radius_m[3],
                     const struct qrt_points *pts, const double q_deg[3])
{
    double p[4][3], best = 1e30;
    long i;
    int k;
    qrt_arm_fk(arm, q_deg, p);
    for (i = 0; i < pts->count; i++) {
        double x[3];
        x[0] = pts->xyz[i][0];
        x[1] = pts->xyz[i][1];
        x[2] = pts->xyz[i][2];
        for (k = 0; k < 3; k++) {
            double c = sqrt(qrt_seg_dist2(x, p[k], p[k + 1])) - radius_m[k];
            if (c < best)
                best = c;
        }
    }
    return best;
}

int qrt_motion_free_exact(const struct qrt_arm *arm, const double radius_m[3],
                          const struct qrt_points *pts,
                          const struct qrt_lattice *lat, const double a_deg[3],
                          const double b_deg[3], int max_steps)
{
    const double *l = arm->link_m;
    double d[3], speed, t = 0.0;
    int step, j;
    qrt_motion_delta(lat, a_deg, b_deg, d);
    /* No point of the arm moves faster than this (metres per unit t): each
     * joint's rate times the farthest any arm point is from its axis. */
    speed = (fabs(d[0]) * (l[0] + l[1] + l[2]) + fabs(d[1]) * (l[1] + l[2]) +
             fabs(d[2]) * l[2]) *
            QRT_DEG;
    for (step = 0; step < max_steps; step++) {
        double q[3], c;
        for (j = 0; j < 3; j++)
            q[j] = a_deg[j] + t * d[j];
        c = qrt_clearance(arm, radius_m, pts, q);
        if (c <= 1e-7)
            return 0;
        if (speed <= 0.0)
            return 1;
        t += c / speed;
        if (t >= 1.0)
            return 1;
    }
    return 0;
}
