/* The paper's obstacle family (its Eq. 13 and Fig. 17). */
#ifndef QRT_CLI_GEN_H
#define QRT_CLI_GEN_H

struct sphere_layout {
    int spheres;       /* n */
    int points;        /* inspection points per sphere, k*k */
    double radius_m;   /* L of Eq. 13 */
    double distance_m; /* centres this far from the base axis */
    double height_m;   /* centres at this z */
    double phase_deg;  /* bearing of the first centre */
};

void sphere_layout_default(struct sphere_layout *L);

/* Points per side k = round(sqrt(points)) (at least 2), so a sphere has k*k
 * points. */
int sphere_side(const struct sphere_layout *L);

/* Total points the layout makes. */
long sphere_layout_count(const struct sphere_layout *L);

/* Fill xyz (3 doubles a point, sphere_layout_count points): sphere i is
 * centred at bearing phase + 360 i / n on a circle of distance_m around the
 * base, at height_m; its points are Eq. 13 with theta1 over [-180, 180) and
 * theta2 over [-90, 90] in k equal steps each. */
void sphere_layout_points(const struct sphere_layout *L, double *xyz);

#endif
