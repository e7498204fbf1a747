/* The goal region's A* estimate (perimeter search, src/core/search.c)
 * against the truth on random masks: every node's true cost to the goal,
 * from a Dijkstra written here (its own heap), must bound the estimate from
 * above (admissible), the estimate may drop by no more than a move's cost
 * from a node to a free neighbour (consistent), the region's own costs
 * must be exact, the estimate may be infinite only where the goal cannot
 * be reached (and must be wherever the region holds the goal's whole
 * component), and A* must find the true
 * shortest path. The masks are written bit by bit (boxes, walls with
 * holes, cages round the goal with and without a way in), so that goals
 * sit in pockets, where the region is taken, and in closed components. */
#include <string.h>

#include "../../src/core/bits.h"
#include "../../src/core/search.h"
#include "check.h"
#include "qrtplan/qrtplan.h"
#include "ref_lattice.h"

static struct qrt_planner pl;
static double to_goal[QRT_MAX_NODES];
static long heap_node[QRT_MAX_NODES], heap_at[QRT_MAX_NODES];
static long heap_len;

static void heap_swap(long i, long j)
{
    long t = heap_node[i];
    heap_node[i] = heap_node[j];
    heap_node[j] = t;
    heap_at[heap_node[i]] = i;
    heap_at[heap_node[j]] = j;
}

static void heap_up(long i)
{
    while (i > 0 && to_goal[heap_node[(i - 1) / 2]] > to_goal[heap_node[i]]) {
        heap_swap(i, (i - 1) / 2);
        i = (i - 1) / 2;
    }
}

static long heap_pop(void)
{
    long top = heap_node[0], i = 0;
    heap_swap(0, --heap_len);
    heap_at[top] = -2;
    for (;;) {
        long c = 2 * i + 1;
        if (c >= heap_len)
            break;
        if (c + 1 < heap_len &&
            to_goal[heap_node[c + 1]] < to_goal[heap_node[c]])
            c++;
        if (to_goal[heap_node[c]] >= to_goal[heap_node[i]])
            break;
        heap_swap(i, c);
        i = c;
    }
    return top;
}

/* Every free node's cost to the goal node (HUGE_VAL: none). */
static void true_costs(const struct qrt_mask *m, long goal)
{
    const struct qrt_lattice *lat = &m->lat;
    long n = qrt_lattice_node_count(lat), i;
    for (i = 0; i < n; i++) {
        to_goal[i] = HUGE_VAL;
        heap_at[i] = -1;
    }
    to_goal[goal] = 0.0;
    heap_len = 1;
    heap_node[0] = goal;
    heap_at[goal] = 0;
    while (heap_len > 0) {
        long u = heap_pop();
        int c[3], d;
        qrt_lattice_coords(lat, u, c);
        for (d = 0; d < 27; d++) {
            int da = d / 9 - 1, ds = (d / 3) % 3 - 1, de = d % 3 - 1;
            long v = wrap_index(lat, c[0] + da, c[1] + ds, c[2] + de);
            double w;
            if (d == 13 || v < 0 || qrt_mask_blocked_index(m, v) ||
                heap_at[v] == -2)
                continue;
            w = lat->grid_deg * sqrt((double)(da * da + ds * ds + de * de));
            if (to_goal[u] + w >= to_goal[v])
                continue;
            to_goal[v] = to_goal[u] + w;
            if (heap_at[v] < 0) {
                heap_node[heap_len] = v;
                heap_at[v] = heap_len++;
            }
            heap_up(heap_at[v]);
        }
    }
}

static void set_blocked(struct qrt_mask *m, int a, int s, int e)
{
    long v = wrap_index(&m->lat, a, s, e);
    int c[3];
    if (v < 0)
        return;
    qrt_lattice_coords(&m->lat, v, c);
    qrt_bit_set(m->rows[c[0]][c[1]], c[2]);
}

static void clear_node(struct qrt_mask *m, const int c[3])
{
    qrt_bit_clear(m->rows[c[0]][c[1]], c[2]);
}

static int pick(int n)
{
    return (int)test_uniform(0.0, n - 1e-9);
}

/* Boxes and walls with holes everywhere; around the goal, sometimes a
 * cage: a shell of blocked nodes, closed or with one way in. */
static void random_mask(struct qrt_mask *m, int goal[3], int *caged,
                        int door_cage)
{
    const int *n = m->lat.n;
    int boxes = 5 + pick(30), walls = pick(3), b, a, s, e, k;
    for (b = 0; b < boxes; b++) {
        int lo[3], len[3];
        for (k = 0; k < 3; k++) {
            len[k] = 1 + pick(8);
            lo[k] = pick(n[k]);
        }
        for (a = 0; a < len[0]; a++)
            for (s = 0; s < len[1]; s++)
                for (e = 0; e < len[2]; e++)
                    set_blocked(m, lo[0] + a, lo[1] + s, lo[2] + e);
    }
    for (b = 0; b < walls; b++) { /* a wall across sigma with two holes */
        int at = pick(n[1]), hole[2][2];
        for (k = 0; k < 2; k++) {
            hole[k][0] = pick(n[0]);
            hole[k][1] = pick(n[2]);
        }
        for (a = 0; a < n[0]; a++)
            for (e = 0; e < n[2]; e++)
                if (!((a == hole[0][0] && e == hole[0][1]) ||
                      (a == hole[1][0] && e == hole[1][1])))
                    set_blocked(m, a, at, e);
    }
    for (k = 0; k < 3; k++)
        goal[k] = pick(n[k]);
    *caged = test_uniform(0.0, 1.0) < 0.4 || door_cage;
    if (*caged) {
        int r = 1 + pick(3), door = test_uniform(0.0, 1.0) < 0.5, d[3];
        if (door_cage) { /* small, so that the region reaches the door */
            door = 1;
            r = 1 + pick(2);
        }
        for (d[0] = -r; d[0] <= r; d[0]++)
            for (d[1] = -r; d[1] <= r; d[1]++)
                for (d[2] = -r; d[2] <= r; d[2]++) {
                    int on = abs(d[0]) == r || abs(d[1]) == r || abs(d[2]) == r;
                    /* the way in: one node of the shell's +alpha face */
                    if (on && !(door && d[0] == r && d[1] == 0 && d[2] == 0))
                        set_blocked(m, goal[0] + d[0], goal[1] + d[1],
                                    goal[2] + d[2]);
                }
    }
    clear_node(m, goal);
}

int main(void)
{
    int trial, used = 0, enclosed = 0, compared = 0;
    long fewer = 0;
    test_seed(9090);
    for (trial = 0; trial < test_count(120); trial++) {
        struct qrt_params prm;
        struct qrt_target st, gt;
        struct qrt_plan plan;
        struct qrti_goal_region region;
        const struct qrt_lattice *lat;
        int goal[3], start[3], caged, c[3], d, tries;
        long n, i, si, gi, bad_bound = 0, bad_step = 0, bad_inf = 0,
                           bad_exact = 0;
        qrt_params_default(&prm);
        prm.grid_deg = 10.0;
        prm.simplify = 0; /* always search: no straight motion first */
        /* the lattice's own answer: the mask is painted by hand over no
         * points, which the sampled fallback would rightly cross */
        prm.sample_draws = 0;
        CHECK(qrt_planner_init(&pl, &prm) == QRT_OK, "init");
        CHECK(qrt_planner_build_mask(&pl) == QRT_OK, "empty mask");
        lat = &pl.mask.lat;
        /* the first trials cage the goal with a way in, where the region
         * is taken, so that a run of a twentieth of the cases (ARM under
         * qemu, the bare-metal board) exercises it too */
        random_mask(&pl.mask, goal, &caged, trial < 6);
        for (tries = 0;; tries++) { /* a free start, not the goal */
            for (d = 0; d < 3; d++)
                start[d] = pick(lat->n[d]);
            if (!qrt_mask_blocked(&pl.mask, start) &&
                (start[0] != goal[0] || start[1] != goal[1] ||
                 start[2] != goal[2]))
                break;
        }
        st.kind = gt.kind = QRT_TARGET_JOINTS;
        qrt_lattice_joints(lat, start, st.value);
        qrt_lattice_joints(lat, goal, gt.value);
        si = qrt_lattice_index(lat, start);
        gi = qrt_lattice_index(lat, goal);
        CHECK(qrt_planner_plan(&pl, &st, &gt, &plan) == QRT_OK, "plan");
        region = pl.goal_region;
        true_costs(&pl.mask, gi);
        if (to_goal[si] == HUGE_VAL) {
            CHECK(plan.status == QRT_STATUS_NO_PATH,
                  "trial %d: no path, the planner says %s", trial,
                  qrt_plan_status_name(plan.status));
        } else {
            CHECK(plan.status == QRT_STATUS_OK &&
                      fabs(plan.lattice_cost_deg - to_goal[si]) < 1e-3,
                  "trial %d: A* %s %.6f, true shortest %.6f", trial,
                  qrt_plan_status_name(plan.status), plan.lattice_cost_deg,
                  to_goal[si]);
        }
        CHECK(region.settled > 0 && region.node[0] == gi &&
                  region.cost[0] == 0.0f,
              "trial %d: the region starts at the goal", trial);
        for (i = 0; i < region.settled; i++)
            if (fabs((double)region.cost[i] - to_goal[region.node[i]]) > 1e-3)
                bad_exact++;
        /* the estimate at every free node, and across every move */
        n = qrt_lattice_node_count(lat);
        for (i = 0; i < n; i++) {
            double h;
            if (qrt_mask_blocked_index(&pl.mask, i))
                continue;
            qrt_lattice_coords(lat, i, c);
            h = qrt_goal_region_estimate(&pl, c);
            if (to_goal[i] < HUGE_VAL && h > to_goal[i] + 1e-3)
                bad_bound++;
            /* infinite only where the goal is out of reach; and where the
             * region holds the goal's whole component (no rim), there */
            if ((h == HUGE_VAL && to_goal[i] < HUGE_VAL) ||
                (region.rim == 0 && h < HUGE_VAL && to_goal[i] == HUGE_VAL))
                bad_inf++;
            for (d = 0; d < 27 && h < HUGE_VAL; d++) {
                int da = d / 9 - 1, ds = (d / 3) % 3 - 1, de = d % 3 - 1, o[3];
                long v = wrap_index(lat, c[0] + da, c[1] + ds, c[2] + de);
                double w;
                if (d == 13 || v < 0 || qrt_mask_blocked_index(&pl.mask, v))
                    continue;
                qrt_lattice_coords(lat, v, o);
                w = lat->grid_deg * sqrt((double)(da * da + ds * ds + de * de));
                if (h > w + qrt_goal_region_estimate(&pl, o) + 1e-3)
                    bad_step++;
            }
        }
        CHECK(bad_exact == 0, "trial %d: %ld region costs are not exact", trial,
              bad_exact);
        CHECK(bad_bound == 0,
              "trial %d: the estimate exceeds the true cost at %ld nodes",
              trial, bad_bound);
        CHECK(bad_inf == 0,
              "trial %d: %ld nodes infinite where the goal is reachable, "
              "or finite outside a closed region",
              trial, bad_inf);
        CHECK(bad_step == 0,
              "trial %d: the estimate drops by more than a move at %ld "
              "moves",
              trial, bad_step);
        used += region.used;
        enclosed += caged && region.rim == 0;
        if (region.used && plan.status == QRT_STATUS_OK) {
            /* what the region saved: the same plan with plain Dijkstra */
            struct qrt_plan plain;
            pl.params.use_astar = 0;
            CHECK(qrt_planner_plan(&pl, &st, &gt, &plain) == QRT_OK, "plan");
            compared++;
            fewer += plan.nodes_expanded < plain.nodes_expanded;
        }
    }
    printf("region taken in %d trials, goal enclosed in %d, A* with it "
           "expanded fewer than Dijkstra in %ld of %d\n",
           used, enclosed, fewer, compared);
    CHECK(used >= 1 && used >= test_count(120) / 10,
          "the region was taken in %d trials", used);
    CHECK(enclosed >= 1 || test_count(120) < 20,
          "no trial enclosed the goal (%d)", enclosed);
    return test_done("test_goal_region");
}
