#include "gen.h"

#include <math.h>

#define PI 3.14159265358979323846

void sphere_layout_default(struct sphere_layout *L)
{
    L->spheres = 1;
    L->points = 1444;
    L->radius_m = 0.1;
    L->distance_m = 0.6;
    L->height_m = 0.0;
    L->phase_deg = 180.0;
}

int sphere_side(const struct sphere_layout *L)
{
    int k = (int)floor(sqrt((double)L->points) + 0.5);
    return k < 2 ? 2 : k;
}

long sphere_layout_count(const struct sphere_layout *L)
{
    long k = sphere_side(L);
    return (long)L->spheres * k * k;
}

void sphere_layout_points(const struct sphere_layout *L, double *xyz)
{
    int k = sphere_side(L), s, i, j;
    long n = 0;
    for (s = 0; s < L->spheres; s++) {
        double bearing = (L->phase_deg + 360.0 * s / L->spheres) * PI / 180.0;
        double cx = L->distance_m * cos(bearing);
        double cy = L->distance_m * sin(bearing);
        for (i = 0; i < k; i++)
            for (j = 0; j < k; j++) {
                double t1 = -PI + 2.0 * PI * i / k;
                double t2 = -0.5 * PI + PI * j / (k - 1);
                xyz[3 * n] = cx + L->radius_m * cos(t1) * cos(t2);
                xyz[3 * n + 1] = cy + L->radius_m * sin(t1) * cos(t2);
                xyz[3 * n + 2] = L->height_m + L->radius_m * sin(t2);
                n++;
            }
    }
}
