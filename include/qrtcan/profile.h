/* The synchronised trapezoidal profile of one path segment: what the CiA
 * 402 master (qrtcan/master.h) gives its drives for each segment, as pure
 * functions, so that anyone can compute the same motion without a bus
 * (qrtplan setpoints writes it as a CSV of timed joint set-points).
 *
 * A segment is a straight line in joint space from where the joints are
 * by step_deg. Its path parameter s runs from 0 to 1 on a trapezoid: up at
 * accel (1/s^2) to speed (1/s), cruise, down at accel; speed and accel are
 * the largest that keep every moving joint j within its own limits, so
 * joint j follows from + s * step[j] with profile velocity |step[j]| *
 * speed and acceleration = deceleration |step[j]| * accel: every joint
 * starts and stops at the same moments. A joint that does not move gets
 * its full velocity and acceleration (it has nothing to keep pace with).
 *
 * Portable C99 like the rest of qrtcan: no OS calls, no malloc, no stdio.
 */
#ifndef QRTCAN_PROFILE_H
#define QRTCAN_PROFILE_H

#include <stdint.h>

#include "qrtcan/scale.h"

#ifdef __cplusplus
extern "C" {
#endif

#define QRTCAN_JOINTS 3

struct qrtcan_segment {
    double step_deg[QRTCAN_JOINTS];     /* each joint's move */
    double vel_deg_s[QRTCAN_JOINTS];    /* each joint's profile velocity */
    double accel_deg_s2[QRTCAN_JOINTS]; /* its acceleration = deceleration */
    int moves;         /* some joint moves (else the rest is 0) */
    double speed;      /* the path parameter's profile velocity, 1/s */
    double accel;      /* and its acceleration = deceleration, 1/s^2 */
    double peak;       /* the speed it reaches (below speed: a triangle) */
    double ramp_s;     /* time accelerating (= time decelerating) */
    double cruise_s;   /* time at speed between them (0: a triangle) */
    double duration_s; /* 2 ramp_s + cruise_s */
};

/* The step from joints here to waypoint to as the master takes it: alpha
 * (joint 0) the short way round, (-180, 180], so that its drive position
 * stays continuous across +-180 degrees (here's alpha may be beyond
 * them); sigma and eta to - here. */
void qrtcan_segment_step(const double here[QRTCAN_JOINTS],
                         const double to[QRTCAN_JOINTS],
                         double step[QRTCAN_JOINTS]);

/* The segment's profile for joint limits max_speed_deg_s and
 * max_accel_deg_s2 (each > 0 and finite; QRTCAN_E_ARG otherwise, or for a
 * non-finite step). A joint moves when |step| >= 1e-9 degrees. */
int qrtcan_segment_profile(const double max_speed_deg_s[QRTCAN_JOINTS],
                           const double max_accel_deg_s2[QRTCAN_JOINTS],
                           const double step_deg[QRTCAN_JOINTS],
                           struct qrtcan_segment *seg);

/* The path parameter s (0..1) t seconds into the segment (0 before it, 1
 * after it) and, where ds is not NULL, its rate (1/s). */
double qrtcan_segment_fraction(const struct qrtcan_segment *seg, double t,
                               double *ds);

/* The joints t seconds into the segment that starts at from, and (where
 * vel is not NULL) their velocities in degrees a second. */
void qrtcan_segment_at(const struct qrtcan_segment *seg,
                       const double from[QRTCAN_JOINTS], double t,
                       double q[QRTCAN_JOINTS], double *vel);

/* Slowest profile the drives get, in degrees a second (squared): a joint
 * whose share of a segment is tiny would otherwise crawl (at 1 count/s a
 * drive needs seconds to settle its last counts). Leading by that little
 * bounds the detour from the straight segment by the joint's own step. */
#define QRTCAN_FLOOR_SPEED_DEG_S 0.02
#define QRTCAN_FLOOR_ACCEL_DEG_S2 0.04

/* The segment as the drives are told it: profile velocity (0x6081) and
 * acceleration = deceleration (0x6083, 0x6084) in counts a second
 * (squared), each at least the floors above, rounded, 1..4e9. */
void qrtcan_segment_counts(const struct qrtcan_segment *seg,
                           const struct qrtcan_scale scale[QRTCAN_JOINTS],
                           uint32_t vel[QRTCAN_JOINTS],
                           uint32_t acc[QRTCAN_JOINTS]);

/* qrtcan_segment_profile, then qrtcan_segment_counts: the values the
 * master writes for a segment of step_deg (the profile kept off the
 * caller's stack frame). QRTCAN_E_ARG as qrtcan_segment_profile. */
int qrtcan_segment_drive_profile(const double max_speed_deg_s[QRTCAN_JOINTS],
                                 const double max_accel_deg_s2[QRTCAN_JOINTS],
                                 const struct qrtcan_scale scale[QRTCAN_JOINTS],
                                 const double step_deg[QRTCAN_JOINTS],
                                 uint32_t vel[QRTCAN_JOINTS],
                                 uint32_t acc[QRTCAN_JOINTS]);

#ifdef __cplusplus
}
#endif

#endif
