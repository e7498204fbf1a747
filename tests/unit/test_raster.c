/* The conservative raster's promise, checked by brute force: no
 * configuration inside the cell box of a free node collides with any
 * point. For every free node next to a blocked one (where a raster that
 * blocks too little would show) the smallest clearance inside its box is
 * searched for with many starts and a shrinking local search, using the
 * independent reference arm of ref_arm.h. */
#include "box_search.h"
#include "check.h"
#include "qrtplan/qrtplan.h"
#include "ref_arm.h"

static struct qrt_planner pl;

static int has_blocked_neighbour(const struct qrt_mask *m, const int ijk[3])
{
    const struct qrt_lattice *lat = &m->lat;
    int d;
    for (d = 0; d < 27; d++) {
        int nb[3] = {ijk[0] + d / 9 - 1, ijk[1] + (d / 3) % 3 - 1,
                     ijk[2] + d % 3 - 1};
        if (d == 13)
            continue;
        if (lat->alpha_wraps)
            nb[0] = (nb[0] + lat->n[0]) % lat->n[0];
        if (nb[0] < 0 || nb[0] >= lat->n[0] || nb[1] < 0 ||
            nb[1] >= lat->n[1] || nb[2] < 0 || nb[2] >= lat->n[2])
            continue;
        if (qrt_mask_blocked(m, nb))
            return 1;
    }
    return 0;
}

static void random_point(double p[3])
{
    double kind = test_uniform(0.0, 1.0);
    double rho = kind < 0.15 ? test_uniform(0.0, 0.15) /* near the axis */
                             : test_uniform(0.1, 1.0);
    double phi = test_uniform(-3.14159, 3.14159);
    p[0] = rho * cos(phi);
    p[1] = rho * sin(phi);
    p[2] = kind < 0.25 ? test_uniform(-0.05, 0.05) : test_uniform(-0.6, 0.9);
}

/* Share of the free frontier nodes searched; QRT_TEST_FULL=1 takes all. */
static double frontier_share = 0.25;

static void run_case(double grid, double cspace_margin, int npts, long *checked,
                     long *blocked_checked, long *blocked_colliding)
{
    struct qrt_params prm;
    double pts[3 * 16], radius[3];
    long idx, n_nodes, sampled = 0;
    int i, k;
    qrt_params_default(&prm);
    prm.grid_deg = grid;
    prm.cspace_margin_deg = cspace_margin;
    prm.margin_m = test_uniform(0.0, 0.02);
    for (k = 0; k < 3; k++)
        prm.arm.link_radius_m[k] = test_uniform(0.005, 0.04);
    CHECK(qrt_planner_init(&pl, &prm) == QRT_OK, "init");
    for (i = 0; i < npts; i++)
        random_point(pts + 3 * i);
    qrt_planner_add_points(&pl, pts, npts);
    qrt_planner_build_mask(&pl);
    for (k = 0; k < 3; k++)
        radius[k] = prm.arm.link_radius_m[k] + prm.margin_m;
    n_nodes = qrt_lattice_node_count(&pl.mask.lat);
    for (idx = 0; idx < n_nodes; idx++) {
        int ijk[3];
        double centre[3], worst[3], c;
        int blocked;
        qrt_lattice_coords(&pl.mask.lat, idx, ijk);
        blocked = qrt_mask_blocked(&pl.mask, ijk);
        /* every free frontier node; a sample of blocked ones for the
         * tightness figure */
        if (!blocked && (!has_blocked_neighbour(&pl.mask, ijk) ||
                         test_uniform(0.0, 1.0) > frontier_share))
            continue;
        if (blocked && test_uniform(0.0, 1.0) > 0.02)
            continue;
        qrt_lattice_joints(&pl.mask.lat, ijk, centre);
        c = box_min_clearance(pts, npts, radius, centre,
                              0.5 * grid + cspace_margin, 16, 1e-4, worst);
        sampled++;
        if (blocked) {
            (*blocked_checked)++;
            *blocked_colliding += c < 0.0;
            continue;
        }
        (*checked)++;
        CHECK(c >= 0.0,
              "free node (%g %g %g) grid %g margin %g: config (%.4f %.4f "
              "%.4f) has clearance %.3g m",
              centre[0], centre[1], centre[2], grid, cspace_margin, worst[0],
              worst[1], worst[2], c);
    }
    (void)sampled;
}

int main(void)
{
    static const double grids[3] = {5.0, 10.0, 20.0};
    long checked = 0, blocked_checked = 0, blocked_colliding = 0;
    int trial;
    test_seed(12345);
    frontier_share *= (double)test_count(1000) / 1000.0;
    if (getenv("QRT_TEST_FULL"))
        frontier_share = 1.0;
    for (trial = 0; trial < 24; trial++)
        run_case(grids[trial % 3], trial % 4 == 3 ? 2.5 : 0.0, 1 + trial % 6,
                 &checked, &blocked_checked, &blocked_colliding);
    printf("free frontier nodes checked: %ld; blocked nodes sampled: %ld, "
           "of which a collision was found in the box: %.1f%%\n",
           checked, blocked_checked,
           100.0 * blocked_colliding / (blocked_checked ? blocked_checked : 1));
    CHECK(checked > test_count(1000), "too few nodes checked: %ld", checked);
    /* tightness: a raster that blocks far too much fails here */
    CHECK(blocked_colliding > 0.6 * blocked_checked,
          "only %ld of %ld sampled blocked nodes really collide",
          blocked_colliding, blocked_checked);
    return test_done("test_raster");
}
