/* Compile-time settings of the planning core.
 *
 * Every table in the core is sized from these numbers, so the size of
 * struct qrt_planner is known at compile time and nothing is allocated at run
 * time. Each setting below changes the layout of struct qrt_planner or
 * struct qrt_plan, or the planner's behaviour, so a caller must be compiled
 * with the library's values (the ABI guard in planner.h refuses any other).
 * Set them through the CMake cache variables of the same names: the
 * installed CMake package and pkg-config file then pass the library's
 * values to every consumer. Without CMake, pass the same -D flags to the
 * library and to every caller.
 */
#ifndef QRTPLAN_CONFIG_H
#define QRTPLAN_CONFIG_H

/* Finest lattice spacing the tables are sized for, in whole degrees. A scene
 * may ask for a coarser grid (any spacing >= this one); 20 must be a multiple
 * of it so that the default joint ranges (220, 320 and 360 degrees wide) are
 * whole numbers of cells. */
#ifndef QRT_GRID_DEG_MIN
#define QRT_GRID_DEG_MIN 5
#endif

/* How many obstacle points the point table holds. Past this the table is
 * re-quantised onto a coarser voxel grid (see points.h) rather than
 * overflowing; only when even the coarsest voxels do not fit are points
 * dropped, and the plan then says so. This default is the board's; CMake's
 * host profile (a full build) sets 524288 (docs/embedded.md, Profiles). */
#ifndef QRT_MAX_POINTS
#define QRT_MAX_POINTS 16384
#endif

/* Most waypoints a plan can return. A lattice path is at most as long as the
 * number of free nodes, but after simplification it is short; the planner
 * reports QRT_STATUS_CAPACITY if a simplified path still does not fit. */
#ifndef QRT_MAX_WAYPOINTS
#define QRT_MAX_WAYPOINTS 256
#endif

/* Nodes of the goal region (the nodes nearest the goal, with their exact
 * cost to it, that A* reads its estimate from): more nodes make a better
 * estimate near a goal among obstacles and a longer Dijkstra before A*.
 * A multiple of 4, since A* reads the region in 4-wide lanes. */
#ifndef QRT_GOAL_REGION_NODES
#define QRT_GOAL_REGION_NODES 12
#endif

/* Single-node queries on one alpha node after which its views are indexed
 * by sigma row: the index costs a pass over the views, repaid only when
 * many queries fall on that alpha node. Behaviour only, not layout. */
#ifndef QRT_LAZY_INDEX_AFTER
#define QRT_LAZY_INDEX_AFTER 16
#endif

#if (20 % QRT_GRID_DEG_MIN) != 0
#error "QRT_GRID_DEG_MIN must divide 20"
#endif
#if QRT_MAX_POINTS < 1 || QRT_MAX_POINTS > (1L << 20)
#error "QRT_MAX_POINTS must be in 1 .. 2^20"
#endif
#if QRT_GOAL_REGION_NODES < 4 || QRT_GOAL_REGION_NODES % 4 != 0
#error "QRT_GOAL_REGION_NODES must be a multiple of 4 (A* reads it in lanes)"
#endif

/* Lattice dimensions for the default joint limits at the finest grid; these
 * bound the lattice of any scene. */
#define QRT_MAX_NA (360 / QRT_GRID_DEG_MIN)     /* alpha wraps: -180 == 180 */
#define QRT_MAX_NS (220 / QRT_GRID_DEG_MIN + 1) /* sigma -40 .. 180 */
#define QRT_MAX_NE (320 / QRT_GRID_DEG_MIN + 1) /* eta -180 .. 140 */
#define QRT_MAX_NODES ((long)QRT_MAX_NA * QRT_MAX_NS * QRT_MAX_NE)
/* 64-bit words per eta row of the obstacle mask. */
#define QRT_ROW_WORDS ((QRT_MAX_NE + 63) / 64)

#endif
