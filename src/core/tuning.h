/* The core's tuning constants, in one place. Internal.
 *
 * None of these changes the layout of struct qrt_planner or any result's
 * safety: each trades work in one place for work in another. The settings
 * that size the tables are in qrtplan/config.h. The long reasons are next
 * to the code that reads each constant; the figures that chose them are in
 * docs/performance.md. */
#ifndef QRT_CORE_TUNING_H
#define QRT_CORE_TUNING_H

/* --- clusters (cluster.c, raster.c, lazy.c) --- */

/* Edge of the cubes that group points into clusters (metres): larger
 * clusters share more work, but their bounding balls are less often
 * already covered. */
#ifndef QRT_CLUSTER_CELL_M
#define QRT_CLUSTER_CELL_M 0.05
#endif
/* Fewer points per cluster than this on average and the cubes are made
 * twice as large: one point to a cube shares no work. */
#define QRT_CLUSTER_SPARSE_MEAN 2
/* Most points in one cluster: bounds the member discs' scratch on the
 * stack. */
#define QRT_CLUSTER_MAX 32

/* --- start and goal connections (planner.c, search.h) --- */

/* Most lattice nodes a start or goal is connected to: the search's seeds
 * and goals. */
#define QRT_MAX_ENDS 8
/* Cell shells around its nearest node in which a start or goal looks for a
 * node to connect to: near a surface the conservative cells are blocked
 * and a free end is otherwise stranded. */
#define QRT_CONNECT_SHELLS 3
/* Most advancement steps a connection's proof against the points may take;
 * a connection that needs more is refused, never assumed. */
#define QRT_EXACT_MAX_STEPS 1000

/* --- the sampled fallback (sampled.c) --- */

/* Longest edge a tree grows in one step (joint-space length, degrees):
 * longer edges cross open space in fewer nodes, shorter ones are proved
 * in fewer advancement steps and turn more easily into a passage. */
#define QRT_SAMPLED_STEP_DEG 20.0
/* The generator's seed: any fixed value makes the fallback a function of
 * its inputs. */
#define QRT_SAMPLED_SEED 0x9E3779B97F4A7C15ULL

/* --- conservative advancement (motion.c) --- */

/* Steps after which advancement searches samples of a motion for a
 * colliding one: motions that are often free are mostly proved within a
 * step or two, blocked ones crawl. */
#define QRT_WITNESS_AFTER 4
/* Most clearance one advancement step measures where block boxes are
 * given (metres): a lower cap passes over more blocks whole, and takes
 * more steps in open space. */
#ifndef QRT_BOXED_STEP_CAP_M
#define QRT_BOXED_STEP_CAP_M 0.05
#endif
/* Samples of a motion searched for a colliding configuration. */
#define QRT_WITNESS_SAMPLES 32
/* Points tested against the clearance box at a time, in float over each
 * axis: whole blocks of a scan are far from the arm. */
#define QRT_CLEARANCE_BLOCK 64
/* Blocks whose common box is tried first, passing over them all at once:
 * in the table's Morton order (order.h) a group is a compact patch. */
#define QRT_CLEARANCE_GROUP 64
/* A path's certified clearance (clearance.c) is within half this of the
 * least clearance at the configurations it samples: each step lets the
 * arm move at most this much farther than its clearance exceeds the least
 * one so far. Smaller is tighter and takes more samples. */
#define QRT_CERTIFY_SLACK_M 0.008
/* Clearances more than this above the least one so far are not measured
 * exactly (a sample stops looking at points that far away): they only
 * size the next step, and a lower value makes it shorter, never unsafe. */
#define QRT_CERTIFY_CAP_ABOVE_M 0.05

/* --- the point table's intake (points.c) --- */

/* Points stored and checked in float at a time, as vector code. */
#define QRT_INTAKE_BLOCK 64
/* After a block with a point near the reach, only every this-many-th
 * block is tried in float: where the reach cuts through a scan, most
 * blocks are mixed and the float try is wasted. */
#define QRT_INTAKE_RETRY 8

/* --- the straight motion's proof against the points (sweep.c) --- */

/* Spacing of the stored poses for the arm's fastest point (metres): a
 * point this clear of the arm is passed with them alone. */
#define QRT_SWEEP_POSE_SPACING_M 0.01
/* Steps the proof may take for one point, and over all points (this many
 * a point, plus a start): a motion that brushes past points is left to
 * the mask, which decides it for less. */
#define QRT_SWEEP_STEPS_PER_POINT 64
#define QRT_SWEEP_STEPS_MEAN 4
#define QRT_SWEEP_STEPS_START 1024
/* Every this-many-th point is a sample, tried first: a motion is seldom
 * blocked by one point alone. */
#define QRT_SWEEP_SAMPLE_STRIDE 16
/* Samples near the sweep tried together by one ball first: a scan's
 * samples often form a patch small enough for the ball to clear. */
#define QRT_SWEEP_SAMPLE_RUN 8
/* Entries per block of the off-sweep test (a multiple of the stride). */
#define QRT_SWEEP_OFF_BLOCK 64
/* Points near the sweep tried as one run by one ball, halved down to
 * groups of QRT_SWEEP_RUN_GROUP: a scan's points lie along surfaces in its
 * order. */
#define QRT_SWEEP_RUN_POINTS 32
#define QRT_SWEEP_RUN_GROUP 4
/* A run's ball wider than this (metres) is not tried: it would not clear. */
#define QRT_SWEEP_RUN_BALL_M 0.3
/* Most steps a run's ball may take: a run that brushes past the arm is
 * told sooner point by point. */
#define QRT_SWEEP_RUN_STEPS 32

#endif
