/* A* and index-heap Dijkstra give the same cost as a plain reference
 * Dijkstra (array scan, no heap) written here, on random masks. */
#include "check.h"
#include "qrtplan/qrtplan.h"
#include "ref_lattice.h"

static struct qrt_planner pl;
static double ref_dist[QRT_MAX_NODES];
static unsigned char ref_done[QRT_MAX_NODES];

static double reference_cost(const struct qrt_mask *m, long from, long to)
{
    const struct qrt_lattice *lat = &m->lat;
    long n = qrt_lattice_node_count(lat), i;
    for (i = 0; i < n; i++) {
        ref_dist[i] = 1e30;
        ref_done[i] = 0;
    }
    ref_dist[from] = 0.0;
    for (;;) {
        long u = -1;
        int c[3], d;
        for (i = 0; i < n; i++)
            if (!ref_done[i] && ref_dist[i] < 1e29 &&
                (u < 0 || ref_dist[i] < ref_dist[u]))
                u = i;
        if (u < 0)
            return -1.0;
        if (u == to)
            return ref_dist[u];
        ref_done[u] = 1;
        qrt_lattice_coords(lat, u, c);
        for (d = 0; d < 27; d++) {
            int da = d / 9 - 1, ds = (d / 3) % 3 - 1, de = d % 3 - 1;
            long v = wrap_index(lat, c[0] + da, c[1] + ds, c[2] + de);
            double w =
                lat->grid_deg * sqrt((double)(da * da + ds * ds + de * de));
            if (d == 13 || v < 0 || qrt_mask_blocked_index(m, v))
                continue;
            if (ref_dist[u] + w < ref_dist[v])
                ref_dist[v] = ref_dist[u] + w;
        }
    }
}

static void random_free_node(const struct qrt_mask *m, double q[3], long *idx)
{
    const struct qrt_lattice *lat = &m->lat;
    for (;;) {
        int ijk[3], j;
        for (j = 0; j < 3; j++)
            ijk[j] = (int)test_uniform(0.0, lat->n[j] - 1e-9);
        if (qrt_mask_blocked(m, ijk))
            continue;
        qrt_lattice_joints(lat, ijk, q);
        *idx = qrt_lattice_index(lat, ijk);
        return;
    }
}

int main(void)
{
    int trial, agree = 0, unreachable = 0;
    test_seed(4242);
    for (trial = 0; trial < test_count(60); trial++) {
        struct qrt_params prm;
        struct qrt_target s, g;
        struct qrt_plan plan_a, plan_d;
        double pts[3 * 40];
        long si, gi;
        int i, npts = 5 + trial % 35;
        double ref;
        qrt_params_default(&prm);
        prm.grid_deg = trial % 4 ? 20.0 : 10.0;
        prm.simplify = 0;
        qrt_planner_init(&pl, &prm);
        for (i = 0; i < npts; i++) {
            double rho = test_uniform(0.2, 0.9), phi = test_uniform(-3.1, 3.1);
            pts[3 * i] = rho * cos(phi);
            pts[3 * i + 1] = rho * sin(phi);
            pts[3 * i + 2] = test_uniform(-0.5, 0.8);
        }
        qrt_planner_add_points(&pl, pts, npts);
        qrt_planner_build_mask(&pl);
        s.kind = g.kind = QRT_TARGET_JOINTS;
        random_free_node(&pl.mask, s.value, &si);
        random_free_node(&pl.mask, g.value, &gi);
        ref = reference_cost(&pl.mask, si, gi);
        pl.params.use_astar = 1;
        CHECK(qrt_planner_plan(&pl, &s, &g, &plan_a) == QRT_OK, "plan");
        pl.params.use_astar = 0;
        CHECK(qrt_planner_plan(&pl, &s, &g, &plan_d) == QRT_OK, "plan");
        if (ref < 0.0) {
            unreachable++;
            CHECK(plan_a.status == QRT_STATUS_NO_PATH &&
                      plan_d.status == QRT_STATUS_NO_PATH,
                  "reference finds no path, planner says %s/%s",
                  qrt_plan_status_name(plan_a.status),
                  qrt_plan_status_name(plan_d.status));
            continue;
        }
        CHECK(plan_a.status == QRT_STATUS_OK && plan_d.status == QRT_STATUS_OK,
              "reference finds a path, planner says %s/%s",
              qrt_plan_status_name(plan_a.status),
              qrt_plan_status_name(plan_d.status));
        CHECK(fabs(plan_a.lattice_cost_deg - ref) < 1e-3,
              "A* %.6f vs reference %.6f", plan_a.lattice_cost_deg, ref);
        CHECK(fabs(plan_d.lattice_cost_deg - ref) < 1e-3,
              "Dijkstra %.6f vs reference %.6f", plan_d.lattice_cost_deg, ref);
        CHECK(plan_a.nodes_expanded <= plan_d.nodes_expanded,
              "A* expanded %ld > Dijkstra %ld", plan_a.nodes_expanded,
              plan_d.nodes_expanded);
        agree += fabs(plan_a.lattice_cost_deg - ref) < 1e-3;
    }
    printf("paths compared: %d, no path on both: %d\n", agree, unreachable);
    CHECK(agree >= test_count(60) / 2, "too few solvable cases: %d", agree);
    return test_done("test_search");
}
