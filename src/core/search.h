/* Shortest paths on the free lattice: index-heap Dijkstra or A*. Internal. */
#ifndef QRT_CORE_SEARCH_H
#define QRT_CORE_SEARCH_H

#include "qrtplan/planner.h"
#include "tuning.h"

#define QRT_NO_PARENT 255u

/* Lattice nodes where a path may enter (seeds) or leave (goals), each with
 * the cost of its straight connection to the real start or goal. */
struct qrt_ends {
    int count;
    long node[QRT_MAX_ENDS];
    double cost[QRT_MAX_ENDS];
};

struct qrt_search_result {
    int found;
    long goal_node; /* the lattice node the path leaves from */
    double cost;    /* seed cost + lattice path + goal connection */
    long expanded;  /* nodes taken off the heap */
};

/* Search from the seeds to any goal on pl->mask, leaving the parent of
 * every reached node in pl->parent_dir. With use_astar, a Dijkstra from the
 * goals first settles pl->goal_region, whose estimate A* takes where it
 * says more than octile at a seed; res->expanded counts both searches. */
void qrt_search(struct qrt_planner *pl, const struct qrt_ends *seeds,
                const struct qrt_ends *goals, int use_astar,
                struct qrt_search_result *res);

/* The goal region's estimate of node ijk after a search, in degrees (no
 * slack taken off): the least octile distance to its rim plus the rim
 * node's cost, or the node's own exact cost where it was settled; HUGE_VAL
 * where the goal cannot be reached. For tests. */
double qrt_goal_region_estimate(const struct qrt_planner *pl, const int ijk[3]);

/* Write the node path ending at goal_node (seed first) into
 * pl->open.heap[i].node; returns its length. */
long qrt_search_path(struct qrt_planner *pl, long goal_node);

/* Offset of neighbour direction dir (0..25) on each axis: -1, 0 or 1. */
void qrt_search_direction(int dir, int offset[3]);

#endif
