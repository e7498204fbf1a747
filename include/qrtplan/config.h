/* Compile-time settings of the planning core.
 *
 * Every table in the core is sized from these numbers, so the size of
 * struct qrt_planner is known at compile time and nothing is allocated at run
 * time. Override them with -D on the compiler command line (the CMake options
 * QRT_GRID_DEG_MIN and QRT_MAX_POINTS do that for you).
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
 * dropped, and the plan then says so. */
#ifndef QRT_MAX_POINTS
#define QRT_MAX_POINTS 16384
#endif

/* Most waypoints a plan can return. A lattice path is at most as long as the
 * number of free nodes, but after simplification it is short; the planner
 * reports QRT_STATUS_CAPACITY if a simplified path still does not fit. */
#ifndef QRT_MAX_WAYPOINTS
#define QRT_MAX_WAYPOINTS 256
#endif

#if (20 % QRT_GRID_DEG_MIN) != 0
#error "QRT_GRID_DEG_MIN must divide 20"
#endif
#if QRT_MAX_POINTS < 1 || QRT_MAX_POINTS > (1L << 20)
#error "QRT_MAX_POINTS must be in 1 .. 2^20"
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
