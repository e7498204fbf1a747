/* Clustered rastering (what the planner does) against rastering point by
 * point: the clustered mask must be a subset of the point-by-point one, and
 * every node the clusters leave free that the points alone would block must
 * be truly free (searched by brute force with the reference arm), as must a
 * sample of the clustered mask's free frontier. */
#include "../../src/core/raster.h"
#include "box_search.h"
#include "check.h"
#include "qrtplan/qrtplan.h"
#include "ref_arm.h"

static struct qrt_planner pl;
static struct qrt_mask single;
static double cloud[3 * 3000];

static long make_cloud(int kind)
{
    long n = 0;
    int i, j;
    if (kind == 0) { /* a dense sphere */
        double cx = test_uniform(-0.6, 0.6), cy = test_uniform(-0.6, 0.6);
        for (i = 0; i < 40; i++)
            for (j = 0; j < 40; j++) {
                double t1 = 6.2831853 * i / 40,
                       t2 = -1.5707963 + 3.14159265 * j / 39;
                cloud[3 * n] = cx + 0.12 * cos(t1) * cos(t2);
                cloud[3 * n + 1] = cy + 0.12 * sin(t1) * cos(t2);
                cloud[3 * n + 2] = 0.1 + 0.12 * sin(t2);
                n++;
            }
    } else { /* random blobs of clutter */
        for (i = 0; i < 12; i++) {
            double c[3] = {test_uniform(-0.8, 0.8), test_uniform(-0.8, 0.8),
                           test_uniform(-0.3, 0.7)};
            for (j = 0; j < 120; j++) {
                cloud[3 * n] = c[0] + test_uniform(-0.05, 0.05);
                cloud[3 * n + 1] = c[1] + test_uniform(-0.05, 0.05);
                cloud[3 * n + 2] = c[2] + test_uniform(-0.05, 0.05);
                n++;
            }
        }
    }
    return n;
}

int main(void)
{
    long skipped_total = 0, checked = 0;
    int trial;
    test_seed(8080);
    for (trial = 0; trial < test_count(4); trial++) {
        struct qrt_params prm;
        struct qrt_raster r;
        double radius[3];
        long n = make_cloud(trial % 2), i, idx, nodes, extra = 0, frontier = 0;
        int k;
        qrt_params_default(&prm);
        prm.grid_deg = trial < 3 ? 5.0 : 10.0;
        qrt_planner_init(&pl, &prm);
        qrt_planner_add_points(&pl, cloud, n);
        qrt_planner_build_mask(&pl);
        single.lat = pl.mask.lat;
        qrt_raster_begin(&r, &single, &prm.arm, pl.radius_m, 0.0);
        for (i = 0; i < pl.points.count; i++) {
            double p[3] = {pl.points.x[i], pl.points.y[i], pl.points.z[i]};
            qrt_raster_point(&r, p);
        }
        for (k = 0; k < 3; k++)
            radius[k] = prm.arm.link_radius_m[k] + prm.margin_m;
        nodes = qrt_lattice_node_count(&pl.mask.lat);
        for (idx = 0; idx < nodes; idx++) {
            int a = qrt_mask_blocked_index(&pl.mask, idx);
            int b = qrt_mask_blocked_index(&single, idx);
            int ijk[3];
            double centre[3], worst[3];
            CHECK(!a || b,
                  "clustered mask blocks node %ld that points alone "
                  "leave free",
                  idx);
            if (a || (!b && test_uniform(0, 1) > 0.002))
                continue;
            /* free in the clustered mask: blocked by single points only
             * (always checked, up to 40) or a random free sample */
            if (b && ++extra > 15)
                continue;
            if (!b && ++frontier > 15)
                continue;
            qrt_lattice_coords(&pl.mask.lat, idx, ijk);
            qrt_lattice_joints(&pl.mask.lat, ijk, centre);
            CHECK(box_min_clearance(cloud, n, radius, centre,
                                    0.5 * prm.grid_deg, 12, 2e-3, worst) >= 0.0,
                  "node (%g %g %g) left free by the clusters collides",
                  centre[0], centre[1], centre[2]);
            checked++;
        }
        skipped_total += extra;
    }
    printf("nodes left free only by clustering: %ld; nodes brute-forced: %ld\n",
           skipped_total, checked);
    CHECK(checked >= test_count(4) * 10, "too few nodes checked");
    return test_done("test_cluster");
}
