/* An independent reference of the arm for the C tests: forward kinematics
 * and capsule-point distance written from docs/spec.md sections Kinematics
 * and Collision, sharing no code with the core. */
#ifndef QRT_TEST_REF_ARM_H
#define QRT_TEST_REF_ARM_H

#include <math.h>

static const double REF_L[3] = {0.090, 0.332, 0.538};

static inline void ref_fk(const double q_deg[3], double p[4][3])
{
    const double d = 3.14159265358979323846 / 180.0;
    double a = q_deg[0] * d, s = q_deg[1] * d, e = q_deg[2] * d;
    double ux = cos(a), uy = sin(a);
    p[0][0] = p[0][1] = p[0][2] = 0.0;
    p[1][0] = REF_L[0] * ux;
    p[1][1] = REF_L[0] * uy;
    p[1][2] = 0.0;
    p[2][0] = p[1][0] + REF_L[1] * cos(s) * ux;
    p[2][1] = p[1][1] + REF_L[1] * cos(s) * uy;
    p[2][2] = REF_L[1] * sin(s);
    p[3][0] = p[2][0] + REF_L[2] * cos(s + e) * ux;
    p[3][1] = p[2][1] + REF_L[2] * cos(s + e) * uy;
    p[3][2] = p[2][2] + REF_L[2] * sin(s + e);
}

static inline double ref_seg_dist(const double x[3], const double a[3],
                                  const double b[3])
{
    double ab[3], t = 0.0, len2 = 0.0, d2 = 0.0;
    int i;
    for (i = 0; i < 3; i++) {
        ab[i] = b[i] - a[i];
        len2 += ab[i] * ab[i];
        t += (x[i] - a[i]) * ab[i];
    }
    t = len2 > 0.0 ? t / len2 : 0.0;
    t = t < 0.0 ? 0.0 : (t > 1.0 ? 1.0 : t);
    for (i = 0; i < 3; i++) {
        double c = a[i] + t * ab[i] - x[i];
        d2 += c * c;
    }
    return sqrt(d2);
}

/* Smallest (distance - radius) over links and points. */
static inline double ref_clearance(const double q_deg[3], const double *pts,
                                   long n, const double radius[3])
{
    double p[4][3], best = 1e30;
    long i;
    int k;
    ref_fk(q_deg, p);
    for (i = 0; i < n; i++)
        for (k = 0; k < 3; k++) {
            double c = ref_seg_dist(pts + 3 * i, p[k], p[k + 1]) - radius[k];
            if (c < best)
                best = c;
        }
    return best;
}

#endif
