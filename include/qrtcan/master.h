/* The CiA 402 master that drives the arm's three joints: bring-up, path
 * execution with the profile-position set-point handshake, quick stop, and
 * supervision (heartbeats, SDO answers, drive faults, the bus).
 *
 * Portable C99 like the rest of qrtcan: no OS calls, no malloc, no clock.
 * The caller owns a struct qrtcan_master, hands it every received frame
 * (qrtcan_master_on_frame) and calls qrtcan_master_tick often (every
 * millisecond or two), both with its own monotonic time in microseconds,
 * and sends whatever qrtcan_master_take_frames gives back. The daemon does
 * that over SocketCAN; the tests do it against the simulated drives.
 *
 * Motion between waypoints is a straight line in joint space, as the
 * planner's guarantee assumes (docs/spec.md section Guarantee): for each
 * segment the master gives every drive a trapezoidal profile scaled by that
 * joint's share of the move (profile velocity, acceleration and deceleration by
 * SDO), so all joints start and finish together and the arm stays on the
 * segment up to the drives' following error. Alpha moves the short way
 * round; its drive position is kept continuous (no jump at +-180 degrees).
 * That profile is qrtcan/profile.h's: the master calls qrtcan_segment_step
 * and qrtcan_segment_drive_profile for each segment from where the drives
 * stand; qrtcan_segment_profile and qrtcan_segment_at give its motion in
 * time (qrtplan setpoints).
 */
#ifndef QRTCAN_MASTER_H
#define QRTCAN_MASTER_H

#include <stdint.h>

#include "qrtcan/cia402.h"
#include "qrtcan/frame.h"
#include "qrtcan/profile.h"
#include "qrtcan/scale.h"

#ifdef __cplusplus
extern "C" {
#endif

#define QRTCAN_MASTER_MAX_WAYPOINTS 256
#define QRTCAN_MASTER_OUTBOX 64

struct qrtcan_master_config {
    unsigned node[QRTCAN_JOINTS]; /* drive node ids (default 1, 2, 3) */
    unsigned master_node;         /* our heartbeat's node id (default 127) */
    struct qrtcan_scale scale[QRTCAN_JOINTS];
    double max_speed_deg_s[QRTCAN_JOINTS];  /* per joint (default 30) */
    double max_accel_deg_s2[QRTCAN_JOINTS]; /* per joint (default 60) */
    /* [joint][lo, hi] in degrees: no path leaves them (default the arm's of
     * docs/spec.md section Arm). Alpha wraps, and is not limited, iff
     * [-180, 180]. */
    double limit_deg[QRTCAN_JOINTS][2];
    uint32_t sync_period_us;      /* SYNC + RPDO cycle (default 10 ms) */
    uint32_t master_heartbeat_us; /* our heartbeat period (100 ms) */
    /* how long each drive waits for our heartbeat before it takes its abort
     * connection option: written to its heartbeat consumer 0x1016:1 at
     * bring-up; more than one heartbeat period (3 periods: 300 ms) */
    uint16_t consumer_heartbeat_ms;
    uint16_t drive_heartbeat_ms;   /* asked of each drive (0x1017) (50) */
    uint32_t heartbeat_timeout_us; /* drive declared lost after (300 ms) */
    uint32_t sdo_timeout_us;       /* one SDO attempt (50 ms) */
    unsigned sdo_attempts;         /* before the drive is declared mute (3) */
    uint32_t enable_timeout_us;    /* bring-up to Operation Enabled (2 s) */
    uint32_t retry_after_us;       /* wait before recovering a fault (1 s) */
};

/* Defaults above; scale 1000 counts per degree, offset 0. */
void qrtcan_master_config_default(struct qrtcan_master_config *cfg);

enum qrtcan_master_state {
    QRTCAN_MASTER_OFF,      /* not started, or shut down */
    QRTCAN_MASTER_STARTING, /* NMT + SDO configuration of the drives */
    QRTCAN_MASTER_ENABLING, /* state machine towards Operation Enabled */
    QRTCAN_MASTER_READY,    /* enabled, holding position, no path */
    QRTCAN_MASTER_MOVING,   /* executing a path */
    QRTCAN_MASTER_STOPPED,  /* quick stop commanded; holding */
    QRTCAN_MASTER_FAULT     /* a drive, a heartbeat or the bus failed */
};

/* Why the master stopped or faulted (the latest reason). */
enum qrtcan_master_reason {
    QRTCAN_REASON_NONE,
    QRTCAN_REASON_COMMANDED,      /* qrtcan_master_quick_stop (path blocked) */
    QRTCAN_REASON_DRIVE_FAULT,    /* statusword fault or an EMCY */
    QRTCAN_REASON_HEARTBEAT_LOST, /* a drive's heartbeat went missing */
    QRTCAN_REASON_SDO_TIMEOUT,    /* a drive did not answer an SDO */
    QRTCAN_REASON_SDO_ABORT,      /* a drive refused a configuration write */
    QRTCAN_REASON_ENABLE_TIMEOUT, /* Operation Enabled not reached in time */
    QRTCAN_REASON_BUS,            /* the caller reported a bus error */
    QRTCAN_REASON_SHUTDOWN,
    QRTCAN_REASON_HOST_WATCHDOG /* qrtcan_master_set_host_alive(m, 0) */
};

struct qrtcan_drive {
    unsigned node;
    int heartbeat_seen;
    uint64_t last_heartbeat_us;
    int nmt_state; /* from the heartbeat, -1 before one */
    int tpdo_seen;
    uint16_t statusword;
    int32_t position_counts;
    uint16_t controlword; /* what we send in RPDO1 */
    int32_t target_counts;
    uint16_t last_emcy;
    /* SDO configuration in progress */
    unsigned sdo_step;
    unsigned sdo_attempt;
    int sdo_waiting;
    uint64_t sdo_sent_us;
};

struct qrtcan_master_status {
    enum qrtcan_master_state state;
    enum qrtcan_master_reason reason;
    unsigned reason_node; /* the drive concerned, 0 if none */
    uint16_t reason_code; /* EMCY code or SDO abort low half, if any */
    /* from the drives' TPDOs: the three answers to one SYNC once there are
     * such (so the three angles are of the same moment), else the latest */
    double joints_deg[QRTCAN_JOINTS];
    uint16_t statusword[QRTCAN_JOINTS];
    enum qrtcan_402_state drive_state[QRTCAN_JOINTS];
    int all_positions_known; /* every drive has sent a TPDO */
    int waypoint;            /* index of the waypoint being approached */
    int n_waypoints;
    int path_done; /* the last path reached its goal */
    unsigned long frames_in, frames_ignored, frames_malformed;
    unsigned long frames_out, frames_dropped; /* outbox overflow */
    unsigned long frames_withdrawn;           /* frames a stop made stale */
    unsigned long recoveries;
    int host_alive;         /* qrtcan_master_set_host_alive's last word */
    int heartbeat_produced; /* the master produces its heartbeat now */
};

struct qrtcan_master {
    struct qrtcan_master_config cfg;
    enum qrtcan_master_state state;
    enum qrtcan_master_reason reason;
    unsigned reason_node;
    uint16_t reason_code;
    uint64_t state_since_us, last_sync_us, last_heartbeat_us;
    int started;    /* the caller wants the drives enabled */
    int host_alive; /* the caller's guarding threads run (power-up: 1) */
    struct qrtcan_drive drive[QRTCAN_JOINTS];
    /* the path: waypoints in degrees, the segment being executed */
    double path_deg[QRTCAN_MASTER_MAX_WAYPOINTS][QRTCAN_JOINTS];
    int n_waypoints, waypoint, path_done;
    int segment_phase; /* 0 profiles by SDO, 1 set-point, 2 travel */
    int32_t segment_counts[QRTCAN_JOINTS];      /* the segment's targets */
    uint32_t segment_profile[3][QRTCAN_JOINTS]; /* velocity, accel, decel */
    /* positions the drives sampled at the same SYNC */
    int32_t sync_counts[QRTCAN_JOINTS], coherent_counts[QRTCAN_JOINTS];
    unsigned sync_answers; /* bit j: drive j answered the last SYNC */
    int coherent;
    /* the outbox */
    struct qrtcan_frame out[QRTCAN_MASTER_OUTBOX];
    int out_head, out_count;
    unsigned long frames_in, frames_ignored, frames_malformed;
    unsigned long frames_out, frames_dropped, frames_withdrawn, recoveries;
};

/* QRTCAN_E_ARG for invalid node ids (0, > 127, repeated), bad scales,
 * non-positive speeds, zero periods, or a consumer heartbeat time that is
 * zero or not above the master's heartbeat period. */
int qrtcan_master_init(struct qrtcan_master *m,
                       const struct qrtcan_master_config *cfg, uint64_t now_us);

/* Bring the drives up (NMT, profile position mode, heartbeats, each
 * drive's heartbeat consumer set to watch ours and its abort connection
 * option set to quick stop, both read back) and enable them; the master
 * then holds their position until a path arrives. A drive that refuses
 * any of it is never enabled (QRTCAN_REASON_SDO_ABORT). */
void qrtcan_master_start(struct qrtcan_master *m, uint64_t now_us);

/* On shutdown: quick stop every drive and leave them holding position in
 * Quick Stop Active (not voltage off: an arm without brakes would fall).
 * The master then stops its SYNC and heartbeat, so each drive's heartbeat
 * consumer (0x1016) and SYNC watchdog take over. */
void qrtcan_master_shutdown(struct qrtcan_master *m, uint64_t now_us);

/* A path to execute from where the arm stands. waypoints[0] must be the
 * arm's present position (within 1 degree per joint, else QRTCAN_E_RANGE:
 * the master never makes a move nobody planned), and every waypoint within
 * the joint limits, with each alpha step the short way round where alpha
 * does not wrap (else QRTCAN_E_RANGE: the drives' own limits are the last
 * guard, not the only one). Accepted only with the
 * arm at rest: READY, or STOPPED once every drive reports its quick stop
 * finished (target reached); QRTCAN_E_CMD otherwise (MOVING: stop first,
 * or wait for the path to finish; or the host watchdog holds the arm).
 * QRTCAN_E_ARG for n outside 1..QRTCAN_MASTER_MAX_WAYPOINTS or non-finite
 * values. */
int qrtcan_master_set_path(struct qrtcan_master *m, const double (*wp)[3],
                           int n, uint64_t now_us);

/* 1 if lim ([joint][lo, hi], degrees) is what a config may hold: each low
 * below its high, all within [-180, 180]; qrtcan_master_init checks it. */
int qrtcan_limits_valid(const double (*lim)[2]);

/* The first of the n waypoints outside cfg's joint limits, or after an
 * alpha step the long way round where alpha does not wrap; -1 if none (the
 * test set_path makes, for a caller that would say which). */
int qrtcan_path_outside_limits(const struct qrtcan_master_config *cfg,
                               const double (*wp)[3], int n);

/* Stop now: quick stop to every drive, queued ahead of anything else. The
 * master stays STOPPED until the next path (which re-enables the drives). */
void qrtcan_master_quick_stop(struct qrtcan_master *m, uint64_t now_us);

/* The host's own watchdog: the threads that guard motion on the
 * computer running this master. With alive = 0 the master stops
 * producing its heartbeat, so that every drive's heartbeat consumer
 * (0x1016) expires and the drive takes its abort connection option
 * (0x6007, quick stop); the master also quick-stops the drives itself
 * (reason QRTCAN_REASON_HOST_WATCHDOG), refuses paths (QRTCAN_E_CMD) and
 * does not bring the drives up again until alive = 1. The SYNC goes on,
 * so that the drives' positions are still read. */
void qrtcan_master_set_host_alive(struct qrtcan_master *m, int alive,
                                  uint64_t now_us);

/* The caller's CAN layer failed (interface down, bus-off, no buffer):
 * treated as losing every drive; recovery starts when frames flow again. */
void qrtcan_master_bus_error(struct qrtcan_master *m, uint64_t now_us);

/* A received frame. Returns QRTCAN_OK if it was used, QRTCAN_E_ID if it was
 * not for us (counted as ignored), another negative code if it was ours but
 * malformed (counted; never acted upon). */
int qrtcan_master_on_frame(struct qrtcan_master *m,
                           const struct qrtcan_frame *f, uint64_t now_us);

/* Timeouts, SYNC and heartbeat production, the next step of bring-up and
 * of the set-point handshake. */
void qrtcan_master_tick(struct qrtcan_master *m, uint64_t now_us);

/* Up to max frames to send, oldest first (quick stops first of all). */
int qrtcan_master_take_frames(struct qrtcan_master *m, struct qrtcan_frame *out,
                              int max);

void qrtcan_master_get_status(const struct qrtcan_master *m,
                              struct qrtcan_master_status *st);

const char *qrtcan_master_state_name(enum qrtcan_master_state s);
const char *qrtcan_master_reason_name(enum qrtcan_master_reason r);

#ifdef __cplusplus
}
#endif

#endif
