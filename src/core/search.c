/* Index-heap Dijkstra and A* over the implicit 26-neighbour lattice.
 *
 * No adjacency is stored (the paper's 10^7-entry matrix): a node's
 * neighbours are its index offsets, alpha wrapping around. The heap holds
 * node indices with their keys, and heap_pos gives each node's place in it,
 * so a cheaper route found later lowers the key in place. */
#include "search.h"

#include <math.h>

#include "bits.h"
#include "geom.h"
#include "lazy.h"
#include "mask_bit.h"

void qrt_search_direction(int dir, int offset[3])
{
    int code = dir < 13 ? dir : dir + 1; /* skip 13, the node itself */
    offset[0] = code / 9 - 1;
    offset[1] = (code / 3) % 3 - 1;
    offset[2] = code % 3 - 1;
}

/* heap_pos[node] means something only for a node this search has seen
 * (pushed): the seen bits are cleared per search instead of heap_pos. */
static inline int seen_node(const struct qrt_planner *pl, long node)
{
    return qrt_bit_test(pl->search_seen, node);
}

/* The node's place on the heap, or -1 (never pushed) or -2 (closed). */
static inline int32_t place_of(const struct qrt_planner *pl, long node)
{
    return seen_node(pl, node) ? pl->heap_pos[node] : -1;
}

/* A key's bits, and back. */
static inline uint32_t key_bits(float key)
{
    union {
        float f;
        uint32_t u;
    } k;
    k.f = key;
    return k.u;
}

static inline float key_of(const struct qrti_heap_entry *e)
{
    union {
        float f;
        uint32_t u;
    } k;
    k.u = e->key_bits;
    return k.f;
}

/* An entry's place in the heap's order as one integer: its key's bits,
 * then its node. Keys are never negative, NaN or -0 (a cost so far plus an
 * estimate clamped at +0), and the bits of such floats order as the
 * floats do, so this is the order of (key, node), ties broken by node
 * index so that every platform expands alike; one compare, with no
 * branch, where two compares of floats and a tie test mispredicted. The
 * entry keeps the key as bits behind the node, so that on a little-endian
 * target the compiler reads the two halves as one word. */
static inline uint64_t heap_rank(const struct qrti_heap_entry *e)
{
    return ((uint64_t)e->key_bits << 32) | (uint32_t)e->node;
}

static int heap_less(const struct qrti_heap_entry *a,
                     const struct qrti_heap_entry *b)
{
    return heap_rank(a) < heap_rank(b);
}

static void heap_place(struct qrt_planner *pl, long i, struct qrti_heap_entry e)
{
    pl->open.heap[i] = e;
    pl->heap_pos[e.node] = (int32_t)i;
}

/* The heap is 4-ary: half the levels of a binary one, so a pop follows
 * half as many dependent loads down it (a node's children are 4i+1 ..
 * 4i+4). Any heap pops the same sequence, the order being total. */
static void sift_up(struct qrt_planner *pl, long i)
{
    struct qrti_heap_entry e = pl->open.heap[i];
    while (i > 0) {
        long parent = (i - 1) / 4;
        if (!heap_less(&e, &pl->open.heap[parent]))
            break;
        heap_place(pl, i, pl->open.heap[parent]);
        i = parent;
    }
    heap_place(pl, i, e);
}

static void sift_down(struct qrt_planner *pl, long i, long size)
{
    const struct qrti_heap_entry *h = pl->open.heap;
    struct qrti_heap_entry e = h[i];
    const uint64_t rank = heap_rank(&e);
    for (;;) {
        long c = 4 * i + 1, least = c, j;
        uint64_t least_rank;
        if (c >= size)
            break;
        least_rank = heap_rank(&h[c]);
        /* the least child, by selects rather than branches: of four, as
         * two pairs, so that the compares do not wait on each other */
        if (c + 3 < size) {
            uint64_t r1 = heap_rank(&h[c + 1]), r2 = heap_rank(&h[c + 2]);
            uint64_t r3 = heap_rank(&h[c + 3]);
            long low23 = r3 < r2 ? c + 3 : c + 2;
            uint64_t rank23 = r3 < r2 ? r3 : r2;
            least = r1 < least_rank ? c + 1 : c;
            least_rank = r1 < least_rank ? r1 : least_rank;
            least = rank23 < least_rank ? low23 : least;
            least_rank = rank23 < least_rank ? rank23 : least_rank;
        } else {
            for (j = c + 1; j < size; j++) {
                uint64_t r = heap_rank(&h[j]);
                int less = r < least_rank;
                least = less ? j : least;
                least_rank = less ? r : least_rank;
            }
        }
        if (least_rank >= rank)
            break;
        heap_place(pl, i, h[least]);
        i = least;
    }
    heap_place(pl, i, e);
}

/* Put node on the heap with key, or lower its key if it is there (a key
 * only ever decreases: Dijkstra's decrease-key). */
static void push_or_lower(struct qrt_planner *pl, long *size, long node,
                          float key)
{
    struct qrti_heap_entry e;
    e.key_bits = key_bits(key);
    e.node = (int32_t)node;
    if (place_of(pl, node) >= 0) {
        pl->open.heap[pl->heap_pos[node]] = e;
        sift_up(pl, pl->heap_pos[node]);
    } else {
        qrt_bit_set(pl->search_seen, node);
        /* the lazily built mask keeps its clusters in the heap's tail:
         * finish the mask before the heap grows into them */
        if (qrt_lazy_building(pl) && *size >= QRTI_LAZY_HEAP)
            qrt_lazy_finish(pl);
        pl->open.heap[*size] = e;
        sift_up(pl, (*size)++);
    }
}

/* Length of the shortest obstacle-free 26-neighbour path, in cells: the
 * consistent A* estimate. The steps are sorted by taking the least and the
 * greatest (selects, no branches); the sum is written as it always was, so
 * that every key keeps its bits. */
static inline double octile(int da, int ds, int de)
{
    int lo = da < ds ? da : ds, hi = da < ds ? ds : da, mid;
    lo = de < lo ? de : lo;
    hi = de > hi ? de : hi;
    mid = da + ds + de - lo - hi;
    return sqrt(3.0) * lo + sqrt(2.0) * (mid - lo) + (double)(hi - mid);
}

static inline int axis_gap(const struct qrt_lattice *lat, int j, int a, int b)
{
    int d = a > b ? a - b : b - a;
    if (j == 0 && lat->alpha_wraps && lat->n[0] - d < d)
        d = lat->n[0] - d;
    return d;
}

struct estimate {
    int active;
    int target[3];
    double slack; /* how far a goal candidate may lie from target */
    /* when set: the least octile distance to its rim plus the rim node's
     * cost (perimeter search), instead of the distance to target */
    const struct qrti_goal_region *region;
};

static inline double octile_to(const struct qrt_lattice *lat, const int ijk[3],
                               int a, int s, int e)
{
    return lat->grid_deg * octile(axis_gap(lat, 0, ijk[0], a),
                                  axis_gap(lat, 1, ijk[1], s),
                                  axis_gap(lat, 2, ijk[2], e));
}

/* The goal region's estimate of node (at ijk), in degrees: admissible,
 * because a path from outside the region enters it at a rim node, whose
 * cost is exact, and consistent, because each term changes by at most the
 * octile step and a settled node's own cost is exact. HUGE_VAL where no
 * path can reach the goal (outside a region without a rim: the goal's
 * whole component was settled). In floats over the whole table, without
 * branches, so that the compiler may use vector instructions; the rounding
 * (under 1e-5 steps) is far inside the estimate's slack. */
static double region_estimate(const struct qrti_goal_region *g,
                              const struct qrt_lattice *lat, const int ijk[3],
                              long node)
{
    /* octile = hi + (sqrt 2 - 1) mid + (sqrt 3 - sqrt 2) lo */
    const float k_mid = 0.41421356f, k_lo = 0.31783725f;
    const float a = (float)ijk[0], s = (float)ijk[1], e = (float)ijk[2];
    const float turn = lat->alpha_wraps ? (float)lat->n[0] : 1e9f;
    float terms[QRT_GOAL_REGION_NODES], lane[4], h;
    int i, j;
    for (i = 0; i < QRT_GOAL_REGION_NODES; i++) {
        float da = fabsf(a - g->rim_a[i]), ds = fabsf(s - g->rim_s[i]);
        float de = fabsf(e - g->rim_e[i]), back = turn - da, lo, hi;
        da = back < da ? back : da;
        lo = da < ds ? da : ds;
        lo = lo < de ? lo : de;
        hi = da > ds ? da : ds;
        hi = hi > de ? hi : de;
        terms[i] =
            hi + k_mid * (da + ds + de - lo - hi) + k_lo * lo + g->rim_steps[i];
    }
    /* the least term: four lanes first (vector minimums), then across them
     * (a short chain, where one running minimum would wait on each) */
    for (j = 0; j < 4; j++)
        lane[j] = terms[j];
    for (i = 4; i < QRT_GOAL_REGION_NODES; i += 4)
        for (j = 0; j < 4; j++)
            lane[j] = terms[i + j] < lane[j] ? terms[i + j] : lane[j];
    h = lane[0] < lane[1] ? lane[0] : lane[1];
    h = lane[2] < h ? lane[2] : h;
    h = lane[3] < h ? lane[3] : h;
    if (qrt_bit_test(g->alpha, ijk[0])) {
        for (i = 0; i < g->settled; i++) {
            if (g->node[i] == (int32_t)node) {
                float exact = g->cost[i] / (float)lat->grid_deg;
                h = exact < h ? exact : h;
                break;
            }
        }
    }
    return h >= HUGE_VALF ? HUGE_VAL : (double)h * lat->grid_deg;
}

double qrt_goal_region_estimate(const struct qrt_planner *pl, const int ijk[3])
{
    return region_estimate(&pl->goal_region, &pl->mask.lat, ijk,
                           qrt_lattice_index(&pl->mask.lat, ijk));
}

static inline double estimate_at(const struct estimate *est,
                                 const struct qrt_lattice *lat,
                                 const int ijk[3], long node)
{
    double h;
    if (!est->active)
        return 0.0;
    if (est->region)
        h = region_estimate(est->region, lat, ijk, node);
    else
        h = octile_to(lat, ijk, est->target[0], est->target[1], est->target[2]);
    h -= est->slack;
    return h > 0.0 ? h : 0.0;
}

/* Keys are floats: an estimate stays this far below the true remaining
 * cost, so that rounding never makes it overestimate. */
static double key_slack(const struct qrt_lattice *lat)
{
    return 1e-3 * lat->grid_deg;
}

static void init_estimate(struct estimate *est, const struct qrt_lattice *lat,
                          const struct qrt_ends *goals, int use_astar)
{
    int i, c[3];
    est->active = use_astar && goals->count > 0;
    est->slack = 0.0;
    est->region = NULL;
    if (!est->active)
        return;
    qrt_lattice_coords(lat, goals->node[0], est->target);
    for (i = 1; i < goals->count; i++) {
        double gap;
        qrt_lattice_coords(lat, goals->node[i], c);
        gap = octile_to(lat, c, est->target[0], est->target[1], est->target[2]);
        if (gap > est->slack)
            est->slack = gap;
    }
    est->slack += key_slack(lat);
}

static int goal_slot(const struct qrt_ends *goals, long node)
{
    int i;
    for (i = 0; i < goals->count; i++)
        if (goals->node[i] == node)
            return i;
    return -1;
}

/* Neighbour of ijk in direction off, or -1 outside the lattice. */
static long neighbour(const struct qrt_lattice *lat, const int ijk[3],
                      const signed char off[3], int out[3])
{
    int j;
    for (j = 0; j < 3; j++) {
        out[j] = ijk[j] + off[j];
        if (j == 0 && lat->alpha_wraps) {
            if (out[0] < 0)
                out[0] += lat->n[0];
            else if (out[0] >= lat->n[0])
                out[0] -= lat->n[0];
        } else if (out[j] < 0 || out[j] >= lat->n[j]) {
            return -1;
        }
    }
    return qrt_lattice_index(lat, out);
}

/* The lattice's 26 moves: offsets, index deltas (valid off every face)
 * and costs, and for each axis and sign the moves that step that way on
 * it (bit d of toward[axis][sign > 0]). Small types: the search's frame
 * lies under every row build (stack budget). */
struct moves {
    float cost[26];
    int32_t delta[26];
    uint32_t toward[3][2];
    signed char offset[26][3];
};

static void init_moves(const struct qrt_lattice *lat, struct moves *mv)
{
    int d, j;
    for (j = 0; j < 3; j++)
        mv->toward[j][0] = mv->toward[j][1] = 0;
    for (d = 0; d < 26; d++) {
        int off[3], moved;
        qrt_search_direction(d, off);
        for (j = 0; j < 3; j++) {
            mv->offset[d][j] = (signed char)off[j];
            if (off[j] != 0)
                mv->toward[j][off[j] > 0] |= 1UL << d;
        }
        moved = (off[0] != 0) + (off[1] != 0) + (off[2] != 0);
        mv->cost[d] = (float)(lat->grid_deg * sqrt((double)moved));
        mv->delta[d] =
            (int32_t)(((long)off[0] * lat->n[1] + off[1]) * lat->n[2] + off[2]);
    }
}

/* The moves out of a node reached by move `came` that can lower a cost:
 * those that leave its parent's neighbourhood, stepping on some axis the
 * way `came` stepped. Every other neighbour v is also one of the parent's.
 * The parent, expanded (and closed) with the cost this node's was made
 * from, offered v a cost less by at least 2 - sqrt(3) steps (one move of
 * at most sqrt 3 against two of at least 1 each), or, where it did not try
 * v, its own parent offered less still. Float rounding is far too small to
 * undo that gap: a relaxation through this node would be refused, so it is
 * not tried. */
static uint32_t moves_after(const struct moves *mv, unsigned came)
{
    uint32_t out = 0;
    int j;
    if (came == QRT_NO_PARENT)
        return (1UL << 26) - 1U;
    for (j = 0; j < 3; j++)
        if (mv->offset[came][j] != 0)
            out |= mv->toward[j][mv->offset[came][j] > 0];
    return out;
}

/* The moves from ijk that stay on the lattice: all but those stepping off
 * a face, alpha's ends being faces only where it does not wrap. A node on
 * a face then takes its moves as an inside node does, but for the index of
 * a move across alpha's wrap (where node n[0] is node 0 again). */
static uint32_t moves_on(const struct qrt_lattice *lat, const struct moves *mv,
                         const int ijk[3])
{
    uint32_t on = (1UL << 26) - 1U;
    int j;
    for (j = lat->alpha_wraps ? 1 : 0; j < 3; j++) {
        if (ijk[j] == 0)
            on &= ~mv->toward[j][0];
        if (ijk[j] == lat->n[j] - 1)
            on &= ~mv->toward[j][1];
    }
    return on;
}

/* The turns to add to alpha coordinate a, one past an end of the lattice
 * after a move across alpha's wrap (moves_on lets one only where alpha
 * wraps): +1 below node 0, -1 above the last, else 0. */
static inline int wrap_turns(const struct qrt_lattice *lat, int a)
{
    if (a < 0)
        return 1;
    return a >= lat->n[0] ? -1 : 0;
}

/* One best-first search from seeds. With goals, it ends when nothing left
 * can beat the best goal reached (res); with region instead, it records the
 * nodes it settles there and ends when the region is full (a Dijkstra from
 * the goal, the graph being undirected). */
static void search_from(struct qrt_planner *pl, const struct moves *mv,
                        const struct qrt_ends *seeds,
                        const struct qrt_ends *goals,
                        const struct estimate *est,
                        struct qrti_goal_region *region,
                        struct qrt_search_result *res)
{
    const struct qrt_lattice *lat = &pl->mask.lat;
    long n_nodes = qrt_lattice_node_count(lat), size = 0, i;
    const long turn = n_nodes; /* the index's step for a turn of alpha */
    double best = HUGE_VAL;
    int inside;
    /* the alpha nodes of the goals: a node on none is no goal */
    uint64_t goal_alpha[QRTI_ALPHA_WORDS] = {0};

    for (i = 0; i < (n_nodes + 63) / 64; i++)
        pl->search_seen[i] = 0;
    for (i = 0; goals && i < goals->count; i++) {
        int c[3];
        qrt_lattice_coords(lat, goals->node[i], c);
        qrt_bit_set(goal_alpha, c[0]);
    }
    for (i = 0; i < seeds->count; i++) {
        long node = seeds->node[i];
        int ijk[3];
        double key;
        qrt_lattice_coords(lat, node, ijk);
        if (place_of(pl, node) >= 0 && pl->search.dist[node] <= seeds->cost[i])
            continue;
        key = seeds->cost[i] + estimate_at(est, lat, ijk, node);
        if (key == HUGE_VAL)
            continue; /* cannot reach the goal */
        pl->search.dist[node] = (float)seeds->cost[i];
        pl->parent_dir[node] = QRT_NO_PARENT;
        push_or_lower(pl, &size, node, (float)key);
    }

    while (size > 0) {
        struct qrti_heap_entry top = pl->open.heap[0];
        long u = top.node;
        int ijk[3], slot, d;
        uint32_t todo;
        if ((double)key_of(&top) >= best)
            break; /* nothing left on the heap can beat the best goal */
        pl->heap_pos[u] = -2;
        size--;
        if (size > 0) {
            pl->open.heap[0] = pl->open.heap[size];
            sift_down(pl, 0, size);
        }
        qrt_lattice_coords(lat, u, ijk);
        /* a node pushed before it was known is asked now, so that only
         * the nodes the search takes are asked, not every neighbour it
         * looks at */
        if (qrt_lazy_known(pl, ijk) ? qrt_mask_bit(&pl->mask, ijk)
                                    : qrt_lazy_node_blocked(pl, ijk))
            continue;
        res->expanded++;
        if (region) {
            region->node[region->settled] = (int32_t)u;
            qrt_bit_set(region->alpha, ijk[0]);
            region->cost[region->settled] = pl->search.dist[u];
            if (++region->settled == QRT_GOAL_REGION_NODES)
                break;
        } else if (qrt_bit_test(goal_alpha, ijk[0]) &&
                   (slot = goal_slot(goals, u)) >= 0 &&
                   (double)pl->search.dist[u] + goals->cost[slot] < best) {
            best = (double)pl->search.dist[u] + goals->cost[slot];
            res->found = 1;
            res->goal_node = u;
            res->cost = best;
        }
        /* off every face of the lattice, no neighbour leaves it or wraps:
         * its index is an offset from u */
        inside = ijk[0] > 0 && ijk[0] < lat->n[0] - 1 && ijk[1] > 0 &&
                 ijk[1] < lat->n[1] - 1 && ijk[2] > 0 && ijk[2] < lat->n[2] - 1;
        todo = moves_after(mv, pl->parent_dir[u]);
        if (!inside)
            todo &= moves_on(lat, mv, ijk);
        for (; todo != 0; todo &= todo - 1U) {
            int nb[3];
            int32_t place;
            long v;
            float g;
            double key;
            d = qrt_lowest_bit(todo);
            v = u + mv->delta[d];
            if (!inside)
                v += turn * wrap_turns(lat, ijk[0] + mv->offset[d][0]);
            /* the tests by index first: most moves end at one of them */
            place = place_of(pl, v);
            if (place == -2)
                continue;
            g = pl->search.dist[u] + mv->cost[d];
            if (place >= 0 && pl->search.dist[v] <= g)
                continue;
            nb[0] = ijk[0] + mv->offset[d][0];
            nb[1] = ijk[1] + mv->offset[d][1];
            nb[2] = ijk[2] + mv->offset[d][2];
            if (!inside)
                nb[0] += lat->n[0] * wrap_turns(lat, nb[0]);
            /* a bit set is final even in a row not built yet; a node not
             * known yet is checked when taken */
            if (qrt_mask_bit(&pl->mask, nb))
                continue;
            key = (double)g + estimate_at(est, lat, nb, v);
            if (key == HUGE_VAL)
                continue; /* cannot reach the goal */
            pl->search.dist[v] = g;
            pl->parent_dir[v] = (uint8_t)d;
            push_or_lower(pl, &size, v, (float)key);
        }
    }
}

/* Is neighbour v (at nb) of a settled node outside the region and free?
 * Settled nodes are closed and free; an unknown node is asked only when
 * ask is set, so that the rim is a function of the mask alone, the same
 * whether the mask is whole or asked as it is read. */
static int free_outside(struct qrt_planner *pl, long v, const int nb[3],
                        int ask)
{
    if (place_of(pl, v) == -2)
        return 0; /* closed: settled, or known to be blocked */
    if (qrt_lazy_known(pl, nb))
        return !qrt_mask_bit(&pl->mask, nb);
    return ask && !qrt_lazy_node_blocked(pl, nb);
}

/* The rim of the region just settled: its nodes with a free neighbour
 * outside it. Read before the next search clears the seen bits. */
static void find_rim(struct qrt_planner *pl, const struct moves *mv,
                     struct qrti_goal_region *g)
{
    const struct qrt_lattice *lat = &pl->mask.lat;
    int i, d, ask;
    g->rim = 0;
    for (i = 0; i < QRT_GOAL_REGION_NODES; i++) {
        g->rim_a[i] = g->rim_s[i] = g->rim_e[i] = 0.0f;
        g->rim_steps[i] = HUGE_VALF; /* padding: no term */
    }
    for (i = 0; i < g->settled; i++) {
        int ijk[3], nb[3], on_rim = 0;
        qrt_lattice_coords(lat, g->node[i], ijk);
        /* the neighbours known first: they cost nothing to read */
        for (ask = 0; ask < 2 && !on_rim; ask++) {
            for (d = 0; d < 26 && !on_rim; d++) {
                long v = neighbour(lat, ijk, mv->offset[d], nb);
                on_rim = v >= 0 && free_outside(pl, v, nb, ask);
            }
        }
        if (!on_rim)
            continue;
        g->rim_a[g->rim] = (float)ijk[0];
        g->rim_s[g->rim] = (float)ijk[1];
        g->rim_e[g->rim] = (float)ijk[2];
        g->rim_steps[g->rim++] = g->cost[i] / (float)lat->grid_deg;
    }
}

/* Does the region's estimate say more than the octile one at any seed? If
 * not, it would cost more than it saves. */
static int region_pays(const struct qrt_planner *pl, const struct estimate *est,
                       const struct qrti_goal_region *g,
                       const struct qrt_ends *seeds)
{
    const struct qrt_lattice *lat = &pl->mask.lat;
    struct estimate with = *est;
    int i, ijk[3];
    with.region = g;
    with.slack = key_slack(lat);
    for (i = 0; i < seeds->count; i++) {
        qrt_lattice_coords(lat, seeds->node[i], ijk);
        if (estimate_at(&with, lat, ijk, seeds->node[i]) >
            estimate_at(est, lat, ijk, seeds->node[i]) + with.slack)
            return 1;
    }
    return 0;
}

void qrt_search(struct qrt_planner *pl, const struct qrt_ends *seeds,
                const struct qrt_ends *goals, int use_astar,
                struct qrt_search_result *res)
{
    const struct qrt_lattice *lat = &pl->mask.lat;
    struct qrti_goal_region *region = &pl->goal_region;
    struct moves mv;
    struct estimate est;
    int i;

    /* the heap may use the whole array, where clusters would be kept */
    if (!qrt_lazy_building(pl) && pl->mask_state == QRT_MASK_PARTIAL)
        pl->mask_state = QRT_MASK_NONE;
    init_moves(lat, &mv);
    init_estimate(&est, lat, goals, use_astar);
    res->found = 0;
    res->goal_node = -1;
    res->cost = HUGE_VAL;
    res->expanded = 0;
    region->settled = region->rim = region->used = 0;
    for (i = 0; i < QRTI_ALPHA_WORDS; i++)
        region->alpha[i] = 0;
    if (est.active) {
        struct estimate none = est;
        none.active = 0;
        search_from(pl, &mv, goals, NULL, &none, region, res);
        find_rim(pl, &mv, region);
        if (region_pays(pl, &est, region, seeds)) {
            region->used = 1;
            est.region = region;
            est.slack = key_slack(lat);
        }
    }
    search_from(pl, &mv, seeds, goals, &est, NULL, res);
}

long qrt_search_path(struct qrt_planner *pl, long goal_node)
{
    const struct qrt_lattice *lat = &pl->mask.lat;
    long len = 0, node = goal_node, i;
    /* walk back from the goal, then reverse in place */
    for (;;) {
        int ijk[3], off[3], prev[3], j;
        unsigned dir = pl->parent_dir[node];
        if (qrt_lazy_building(pl) && len >= QRTI_LAZY_HEAP)
            qrt_lazy_finish(pl); /* as in push_or_lower */
        pl->open.heap[len++].node = (int32_t)node;
        if (dir == QRT_NO_PARENT)
            break;
        qrt_lattice_coords(lat, node, ijk);
        qrt_search_direction((int)dir, off);
        for (j = 0; j < 3; j++)
            prev[j] = ijk[j] - off[j];
        if (lat->alpha_wraps)
            prev[0] = (prev[0] + lat->n[0]) % lat->n[0];
        node = qrt_lattice_index(lat, prev);
    }
    for (i = 0; i < len / 2; i++) {
        int32_t t = pl->open.heap[i].node;
        pl->open.heap[i].node = pl->open.heap[len - 1 - i].node;
        pl->open.heap[len - 1 - i].node = t;
    }
    return len;
}
