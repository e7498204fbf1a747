/* The planner's parameters: the arm, its margins and the lattice spacing. */
#ifndef QRTPLAN_PARAMS_H
#define QRTPLAN_PARAMS_H

#include "qrtplan/arm.h"

#ifdef __cplusplus
extern "C" {
#endif

struct qrt_params {
    struct qrt_arm arm;
    double margin_m;          /* workspace margin added to every radius */
    double cspace_margin_deg; /* Eq. 12 boundary expansion, every joint */
    double grid_deg;          /* lattice spacing */
    int use_astar;            /* 1: A* (same cost as Dijkstra), 0: Dijkstra */
    int simplify;             /* 1: shortcut the lattice path */
    /* random configurations the sampled fallback may draw where the
     * lattice has no path (docs/spec.md section Sampled fallback); 0: no
     * fallback */
    long sample_draws;
};

/* The defaults of docs/spec.md: margin 0.01 m, C-space margin 0, 5 degrees, A*,
 * simplification on, QRT_SAMPLE_DRAWS_DEFAULT draws. */
#define QRT_SAMPLE_DRAWS_DEFAULT 2000
/* Most draws a caller may ask for (qrt_planner_init refuses more). */
#define QRT_SAMPLE_DRAWS_MAX 1000000L
void qrt_params_default(struct qrt_params *params);

#ifdef __cplusplus
}
#endif
#endif
