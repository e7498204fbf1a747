/* The CiA 402 master: see include/qrtcan/master.h. */
#include "qrtcan/master.h"

#include <math.h>
#include <string.h>

#include "qrtcan/emcy.h"
#include "qrtcan/nmt.h"
#include "qrtcan/sdo.h"
#include "qrtcan/sync.h"
#include "qrtplan/joints.h"

/* Objects of the drives (CiA 301 / 402). */
#define OD_HB_CONSUMER 0x1016u
#define OD_HEARTBEAT 0x1017u
#define OD_ABORT_OPTION 0x6007u
#define OD_MODE 0x6060u
#define OD_MODE_DISPLAY 0x6061u
#define OD_POSITION_ACTUAL 0x6064u
#define OD_PROFILE_VELOCITY 0x6081u
#define OD_PROFILE_ACCEL 0x6083u
#define OD_PROFILE_DECEL 0x6084u

#define CW_ENABLED QRTCAN_CW_CMD_ENABLE_OPERATION
/* 0x6007's quick stop: a drive that loses our heartbeat ramps down and
 * holds under torque (the arm has no brakes) */
#define ABORT_OPTION_QUICK_STOP 3u

/* A path's first waypoint must be where the arm is (the daemon plans from
 * the measured joints): a larger gap would be an unplanned motion. */
#define START_TOLERANCE_DEG 1.0
/* waypoints written as text and read back may stray this far past a limit */
#define LIMIT_SLACK_DEG 1e-6

/* One step of an SDO sequence: write the step's value (size bytes), or
 * read; a read with check set must answer the step's value (size bytes),
 * else the drive did not keep what it was told and is not brought up. */
struct sdo_step {
    uint16_t index;
    uint8_t subindex;
    int write;
    uint8_t size;
    int check;
};

/* The safety settings are written and read back before the mode and NMT
 * start: a drive that would not stop when our heartbeat stops is never
 * enabled. */
static const struct sdo_step bringup[] = {
    {OD_HEARTBEAT, 0, 1, 2, 0},       /* the drive's heartbeat period */
    {OD_HB_CONSUMER, 1, 1, 4, 0},     /* watch our heartbeat ... */
    {OD_HB_CONSUMER, 1, 0, 4, 1},     /* ... read back */
    {OD_ABORT_OPTION, 0, 1, 2, 0},    /* quick stop without it ... */
    {OD_ABORT_OPTION, 0, 0, 2, 1},    /* ... read back */
    {OD_MODE, 0, 1, 1, 0},            /* profile position ... */
    {OD_MODE_DISPLAY, 0, 0, 1, 1},    /* ... in force */
    {OD_POSITION_ACTUAL, 0, 0, 4, 0}, /* where to hold */
};
#define BRINGUP_STEPS (sizeof bringup / sizeof bringup[0])

static const struct sdo_step profile[] = {
    {OD_PROFILE_VELOCITY, 0, 1, 4, 0},
    {OD_PROFILE_ACCEL, 0, 1, 4, 0},
    {OD_PROFILE_DECEL, 0, 1, 4, 0},
};
#define PROFILE_STEPS (sizeof profile / sizeof profile[0])

void qrtcan_master_config_default(struct qrtcan_master_config *cfg)
{
    static const double limits[QRTCAN_JOINTS][2] = QRT_ARM_DEFAULT_LIMIT_DEG;
    int j;
    memset(cfg, 0, sizeof *cfg);
    memcpy(cfg->limit_deg, limits, sizeof limits);
    for (j = 0; j < QRTCAN_JOINTS; j++) {
        cfg->node[j] = (unsigned)j + 1u;
        cfg->scale[j].counts_per_deg = 1000.0;
        cfg->scale[j].offset_counts = 0;
        cfg->max_speed_deg_s[j] = 30.0;
        cfg->max_accel_deg_s2[j] = 60.0;
    }
    cfg->master_node = 127;
    cfg->sync_period_us = 10000;
    cfg->master_heartbeat_us = 100000;
    cfg->consumer_heartbeat_ms = 300;
    cfg->drive_heartbeat_ms = 50;
    cfg->heartbeat_timeout_us = 300000;
    cfg->sdo_timeout_us = 50000;
    cfg->sdo_attempts = 3;
    cfg->enable_timeout_us = 2000000;
    cfg->retry_after_us = 1000000;
}

/* --- the outbox --------------------------------------------------------- */

static void push(struct qrtcan_master *m, const struct qrtcan_frame *f)
{
    if (m->out_count == QRTCAN_MASTER_OUTBOX) {
        m->frames_dropped++;
        return;
    }
    m->out[(m->out_head + m->out_count) % QRTCAN_MASTER_OUTBOX] = *f;
    m->out_count++;
}

/* Ahead of everything queued: a stop must not wait behind old set-points. */
static void push_front(struct qrtcan_master *m, const struct qrtcan_frame *f)
{
    if (m->out_count == QRTCAN_MASTER_OUTBOX) {
        m->out_count--; /* the newest queued frame makes room */
        m->frames_dropped++;
    }
    m->out_head =
        (m->out_head + QRTCAN_MASTER_OUTBOX - 1) % QRTCAN_MASTER_OUTBOX;
    m->out[m->out_head] = *f;
    m->out_count++;
}

int qrtcan_master_take_frames(struct qrtcan_master *m, struct qrtcan_frame *out,
                              int max)
{
    int n = 0;
    while (n < max && m->out_count > 0) {
        out[n++] = m->out[m->out_head];
        m->out_head = (m->out_head + 1) % QRTCAN_MASTER_OUTBOX;
        m->out_count--;
        m->frames_out++;
    }
    return n;
}

static void send_rpdo(struct qrtcan_master *m, int j, int urgent)
{
    struct qrtcan_402_rpdo p;
    struct qrtcan_frame f;
    p.controlword = m->drive[j].controlword;
    p.target_position = m->drive[j].target_counts;
    if (qrtcan_402_rpdo_encode(m->drive[j].node, &p, &f) != QRTCAN_OK)
        return;
    if (urgent)
        push_front(m, &f);
    else
        push(m, &f);
}

static void send_all_rpdos(struct qrtcan_master *m)
{
    int j;
    for (j = 0; j < QRTCAN_JOINTS; j++)
        send_rpdo(m, j, 0);
}

/* --- state changes ------------------------------------------------------ */

static void enter(struct qrtcan_master *m, enum qrtcan_master_state s,
                  uint64_t now_us)
{
    m->state = s;
    m->state_since_us = now_us;
}

/* Is f a frame that a stop makes stale: a command to one of our drives (an
 * RPDO1, controlword and target, or an SDO request), or, while the host
 * watchdog holds our heartbeat back, a heartbeat of ours queued before it
 * tripped (it would feed the drives' consumers on)? */
static int stale(const struct qrtcan_master *m, const struct qrtcan_frame *f)
{
    int j;
    if (!m->host_alive && f->id == QRTCAN_FN_HEARTBEAT + m->cfg.master_node)
        return 1;
    for (j = 0; j < QRTCAN_JOINTS; j++)
        if (f->id == QRTCAN_FN_RPDO1 + m->drive[j].node ||
            f->id == QRTCAN_FN_RSDO + m->drive[j].node)
            return 1;
    return 0;
}

/* Take the stale frames out of the outbox, keeping the order of the rest
 * (SYNC, heartbeat, NMT). A set-point RPDO sent after a quick stop carries
 * "enable operation" and would take the drive straight back out of Quick
 * Stop Active (CiA 402 transition 16) and on toward its old target. */
static void withdraw_stale(struct qrtcan_master *m)
{
    int i, kept = 0;
    for (i = 0; i < m->out_count; i++) {
        const struct qrtcan_frame *f =
            &m->out[(m->out_head + i) % QRTCAN_MASTER_OUTBOX];
        if (stale(m, f)) {
            m->frames_withdrawn++;
            continue;
        }
        m->out[(m->out_head + kept) % QRTCAN_MASTER_OUTBOX] = *f;
        kept++;
    }
    m->out_count = kept;
}

/* Quick stop to every drive, first in the outbox, and hold there. */
static void stop_all(struct qrtcan_master *m)
{
    int j;
    withdraw_stale(m);
    for (j = QRTCAN_JOINTS - 1; j >= 0; j--) {
        m->drive[j].controlword = QRTCAN_CW_CMD_QUICK_STOP;
        send_rpdo(m, j, 1);
    }
}

static void fail(struct qrtcan_master *m, enum qrtcan_master_reason why,
                 unsigned node, uint16_t code, uint64_t now_us)
{
    if (m->state == QRTCAN_MASTER_FAULT)
        return; /* the first reason is the one to report */
    m->reason = why;
    m->reason_node = node;
    m->reason_code = code;
    m->n_waypoints = 0;
    stop_all(m);
    enter(m, QRTCAN_MASTER_FAULT, now_us);
}

static void begin_bringup(struct qrtcan_master *m, uint64_t now_us)
{
    int j;
    for (j = 0; j < QRTCAN_JOINTS; j++) {
        struct qrtcan_drive *d = &m->drive[j];
        d->sdo_step = 0;
        d->sdo_attempt = 0;
        d->sdo_waiting = 0;
        d->heartbeat_seen = 0;
        d->tpdo_seen = 0;
        d->last_emcy = 0;
    }
    enter(m, QRTCAN_MASTER_STARTING, now_us);
}

int qrtcan_master_init(struct qrtcan_master *m,
                       const struct qrtcan_master_config *cfg, uint64_t now_us)
{
    int j, k;
    if (!m || !cfg || !qrtcan_node_valid(cfg->master_node) ||
        cfg->sync_period_us == 0 || cfg->master_heartbeat_us == 0 ||
        cfg->consumer_heartbeat_ms == 0 ||
        (uint64_t)cfg->consumer_heartbeat_ms * 1000u <=
            cfg->master_heartbeat_us ||
        cfg->sdo_timeout_us == 0 || cfg->sdo_attempts == 0 ||
        cfg->heartbeat_timeout_us == 0 || !qrtcan_limits_valid(cfg->limit_deg))
        return QRTCAN_E_ARG;
    for (j = 0; j < QRTCAN_JOINTS; j++) {
        double c = cfg->scale[j].counts_per_deg;
        if (!qrtcan_node_valid(cfg->node[j]) ||
            cfg->node[j] == cfg->master_node || !isfinite(c) || c == 0.0 ||
            !(cfg->max_speed_deg_s[j] > 0.0) ||
            !(cfg->max_accel_deg_s2[j] > 0.0) ||
            !isfinite(cfg->max_speed_deg_s[j]) ||
            !isfinite(cfg->max_accel_deg_s2[j]))
            return QRTCAN_E_ARG;
        for (k = 0; k < j; k++)
            if (cfg->node[k] == cfg->node[j])
                return QRTCAN_E_ARG;
    }
    memset(m, 0, sizeof *m);
    m->cfg = *cfg;
    m->host_alive = 1;
    for (j = 0; j < QRTCAN_JOINTS; j++) {
        m->drive[j].node = cfg->node[j];
        m->drive[j].nmt_state = -1;
    }
    enter(m, QRTCAN_MASTER_OFF, now_us);
    m->last_sync_us = now_us;
    m->last_heartbeat_us = now_us;
    return QRTCAN_OK;
}

void qrtcan_master_start(struct qrtcan_master *m, uint64_t now_us)
{
    m->started = 1;
    m->reason = QRTCAN_REASON_NONE;
    if (!m->host_alive) {
        /* no bring-up while the host's guards are stalled: the fault's
         * retry starts it once they run again */
        m->reason = QRTCAN_REASON_HOST_WATCHDOG;
        enter(m, QRTCAN_MASTER_FAULT, now_us);
        return;
    }
    begin_bringup(m, now_us);
}

void qrtcan_master_shutdown(struct qrtcan_master *m, uint64_t now_us)
{
    m->started = 0;
    m->n_waypoints = 0;
    /* quick stop and leave the drives holding: switching the voltage off
     * would let an arm without brakes fall */
    stop_all(m);
    m->reason = QRTCAN_REASON_SHUTDOWN;
    enter(m, QRTCAN_MASTER_OFF, now_us);
}

void qrtcan_master_quick_stop(struct qrtcan_master *m, uint64_t now_us)
{
    if (m->state == QRTCAN_MASTER_OFF || m->state == QRTCAN_MASTER_FAULT)
        return;
    m->n_waypoints = 0;
    if (m->host_alive) { /* else the host watchdog's stop is the reason */
        m->reason = QRTCAN_REASON_COMMANDED;
        m->reason_node = 0;
        m->reason_code = 0;
    }
    stop_all(m);
    enter(m, QRTCAN_MASTER_STOPPED, now_us);
}

static void push_heartbeat(struct qrtcan_master *m, uint64_t now_us)
{
    struct qrtcan_frame f;
    m->last_heartbeat_us = now_us;
    if (qrtcan_heartbeat_encode(m->cfg.master_node, QRTCAN_NMT_OPERATIONAL,
                                &f) == QRTCAN_OK)
        push(m, &f);
}

void qrtcan_master_set_host_alive(struct qrtcan_master *m, int alive,
                                  uint64_t now_us)
{
    if (!alive == !m->host_alive)
        return; /* no news: the stop is queued once, not at every call */
    m->host_alive = alive != 0;
    if (!alive)
        withdraw_stale(m); /* our heartbeats still queued, at least */
    if (m->state == QRTCAN_MASTER_OFF)
        return; /* shut down or not started: the drives are not ours */
    if (alive) {
        /* the next tick's heartbeat (a period has passed) re-arms the
         * drives' consumers; the arm stays stopped until the next path,
         * and a fault's retry waits its full time from now */
        if (m->state == QRTCAN_MASTER_FAULT)
            m->state_since_us = now_us;
        return;
    }
    m->n_waypoints = 0;
    m->reason = QRTCAN_REASON_HOST_WATCHDOG;
    m->reason_node = 0;
    m->reason_code = 0;
    stop_all(m);
    /* enabled drives hold in Quick Stop Active and a path after alive = 1
     * restarts them; a bring-up cut short is done again whole, after a
     * fault's retry */
    if (m->state == QRTCAN_MASTER_READY || m->state == QRTCAN_MASTER_MOVING ||
        m->state == QRTCAN_MASTER_STOPPED)
        enter(m, QRTCAN_MASTER_STOPPED, now_us);
    else if (m->state != QRTCAN_MASTER_FAULT)
        enter(m, QRTCAN_MASTER_FAULT, now_us);
}

void qrtcan_master_bus_error(struct qrtcan_master *m, uint64_t now_us)
{
    if (m->state != QRTCAN_MASTER_OFF)
        fail(m, QRTCAN_REASON_BUS, 0, 0, now_us);
}

/* --- paths ---------------------------------------------------------------*/

/* Do all drives' statuswords have every bit of bits set (set = 1) or at
 * least one of them clear (set = 0)? */
static int all_bits(const struct qrtcan_master *m, uint16_t bits, int set)
{
    int j;
    for (j = 0; j < QRTCAN_JOINTS; j++)
        if (((m->drive[j].statusword & bits) == bits) != set)
            return 0;
    return 1;
}

static double joint_deg(const struct qrtcan_master *m, int j)
{
    double deg = 0.0;
    qrtcan_counts_to_deg(&m->cfg.scale[j], m->drive[j].position_counts, &deg);
    return deg;
}

int qrtcan_limits_valid(const double (*lim)[2])
{
    int j;
    for (j = 0; j < QRTCAN_JOINTS; j++)
        if (!(lim[j][0] < lim[j][1] && lim[j][0] >= -180.0 &&
              lim[j][1] <= 180.0))
            return 0;
    return 1;
}

/* Alpha wraps (and has no limit) as in the planner (docs/spec.md section
 * Arm). */
static int joint_wraps(const struct qrtcan_master_config *cfg, int j)
{
    return j == 0 && qrt_alpha_wraps(cfg->limit_deg[0]);
}

/* Limits are a box, so a straight step between two waypoints inside stays
 * inside; an alpha that does not wrap must also step the short way
 * (-180, 180], as the drives will take it: a longer step would turn the
 * other way, through its dead zone. */
int qrtcan_path_outside_limits(const struct qrtcan_master_config *cfg,
                               const double (*wp)[3], int n)
{
    int i, j;
    for (i = 0; i < n; i++)
        for (j = 0; j < QRTCAN_JOINTS; j++) {
            const double *lim = cfg->limit_deg[j];
            if (joint_wraps(cfg, j))
                continue;
            if (!(wp[i][j] >= lim[0] - LIMIT_SLACK_DEG &&
                  wp[i][j] <= lim[1] + LIMIT_SLACK_DEG))
                return i;
            if (j == 0 && i > 0 &&
                !(wp[i][0] - wp[i - 1][0] > -180.0 &&
                  wp[i][0] - wp[i - 1][0] <= 180.0))
                return i;
        }
    return -1;
}

int qrtcan_master_set_path(struct qrtcan_master *m, const double (*wp)[3],
                           int n, uint64_t now_us)
{
    int i, j;
    if (n < 1 || n > QRTCAN_MASTER_MAX_WAYPOINTS)
        return QRTCAN_E_ARG;
    for (i = 0; i < n; i++)
        for (j = 0; j < QRTCAN_JOINTS; j++)
            if (!isfinite(wp[i][j]))
                return QRTCAN_E_ARG;
    if (qrtcan_path_outside_limits(&m->cfg, wp, n) >= 0)
        return QRTCAN_E_RANGE;
    if ((m->state != QRTCAN_MASTER_READY &&
         m->state != QRTCAN_MASTER_STOPPED) ||
        !m->host_alive)
        return QRTCAN_E_CMD;
    if (m->state == QRTCAN_MASTER_STOPPED &&
        !all_bits(m, QRTCAN_SW_TARGET_REACHED, 1))
        return QRTCAN_E_CMD; /* still ramping down */
    for (j = 0; j < QRTCAN_JOINTS; j++) {
        double here = joint_deg(m, j), gap = wp[0][j] - here;
        if (j == 0)
            gap = qrt_wrap_deg(gap);
        if (fabs(gap) > START_TOLERANCE_DEG)
            return QRTCAN_E_RANGE;
    }
    memcpy(m->path_deg, wp, (size_t)n * sizeof wp[0]);
    m->n_waypoints = n;
    m->waypoint = 0;
    m->path_done = 0;
    m->reason = QRTCAN_REASON_NONE;
    m->segment_phase = -1; /* (re-)enable first */
    enter(m, QRTCAN_MASTER_ENABLING, now_us);
    return QRTCAN_OK;
}

/* Targets of the segment from where the drives are to the current
 * waypoint. Alpha's drive position is continuous: its target is the
 * present position plus the short-way step, so crossing +-180 degrees is a
 * small move, not a turn the other way round. */
static int segment_targets(struct qrtcan_master *m, double d[3],
                           int32_t counts[3])
{
    const double *to = m->path_deg[m->waypoint];
    double target[3], here[3];
    int j;
    for (j = 0; j < QRTCAN_JOINTS; j++)
        here[j] = joint_deg(m, j);
    qrtcan_segment_step(here, to, d);
    for (j = 0; j < QRTCAN_JOINTS; j++)
        target[j] = here[j] + d[j];
    for (j = 0; j < QRTCAN_JOINTS; j++)
        if (qrtcan_deg_to_counts(&m->cfg.scale[j], target[j], &counts[j]) !=
            QRTCAN_OK)
            return 0;
    return 1;
}

/* --- SDO sequences -------------------------------------------------------*/

static void sdo_send(struct qrtcan_master *m, int j, const struct sdo_step *st,
                     uint32_t value, uint64_t now_us)
{
    struct qrtcan_sdo s;
    struct qrtcan_frame f;
    s.type = st->write ? QRTCAN_SDO_WRITE : QRTCAN_SDO_READ;
    s.index = st->index;
    s.subindex = st->subindex;
    s.size = st->write ? st->size : 0;
    s.data = st->write ? value : 0;
    if (qrtcan_sdo_encode_request(m->drive[j].node, &s, &f) != QRTCAN_OK)
        return;
    push(m, &f);
    m->drive[j].sdo_waiting = 1;
    m->drive[j].sdo_sent_us = now_us;
}

/* What a bring-up step writes, or what its checked read must answer. */
static uint32_t bringup_value(const struct qrtcan_master *m, unsigned step)
{
    switch (bringup[step].index) {
    case OD_HEARTBEAT:
        return m->cfg.drive_heartbeat_ms;
    case OD_HB_CONSUMER: /* CiA 301: node id in bits 23..16, ms in 15..0 */
        return ((uint32_t)m->cfg.master_node << 16) |
               (uint32_t)m->cfg.consumer_heartbeat_ms;
    case OD_ABORT_OPTION:
        return ABORT_OPTION_QUICK_STOP;
    case OD_MODE:
    case OD_MODE_DISPLAY:
        return QRTCAN_MODE_PROFILE_POSITION;
    default:
        return 0;
    }
}

/* The low size bytes of v (an SDO value of that size). */
static uint32_t sized(uint32_t v, uint8_t size)
{
    switch (size) {
    case 1:
        return v & 0xFFu;
    case 2:
        return v & 0xFFFFu;
    default:
        return v;
    }
}

/* Next step of each drive's SDO sequence; returns whether all are done. */
static int run_sdo(struct qrtcan_master *m, const struct sdo_step *steps,
                   unsigned n, const uint32_t values[][3], uint64_t now_us)
{
    int j, done = 1;
    for (j = 0; j < QRTCAN_JOINTS; j++) {
        struct qrtcan_drive *d = &m->drive[j];
        if (d->sdo_step >= n)
            continue;
        done = 0;
        if (d->sdo_waiting) {
            if (now_us - d->sdo_sent_us < m->cfg.sdo_timeout_us)
                continue;
            if (++d->sdo_attempt >= m->cfg.sdo_attempts) {
                fail(m, QRTCAN_REASON_SDO_TIMEOUT, d->node,
                     steps[d->sdo_step].index, now_us);
                return 0;
            }
        }
        sdo_send(m, j, &steps[d->sdo_step],
                 values ? values[d->sdo_step][j]
                        : bringup_value(m, d->sdo_step),
                 now_us);
    }
    return done;
}

static void sdo_answer(struct qrtcan_master *m, int j,
                       const struct qrtcan_sdo *s, uint64_t now_us)
{
    struct qrtcan_drive *d = &m->drive[j];
    const struct sdo_step *steps;
    unsigned n;
    if (m->state == QRTCAN_MASTER_STARTING) {
        steps = bringup;
        n = BRINGUP_STEPS;
    } else if (m->state == QRTCAN_MASTER_MOVING && m->segment_phase == 0) {
        steps = profile;
        n = PROFILE_STEPS;
    } else {
        m->frames_ignored++; /* a late answer to an abandoned request */
        return;
    }
    if (!d->sdo_waiting || d->sdo_step >= n ||
        s->index != steps[d->sdo_step].index ||
        s->subindex != steps[d->sdo_step].subindex) {
        m->frames_ignored++;
        return;
    }
    if (s->type == QRTCAN_SDO_ABORT) {
        fail(m, QRTCAN_REASON_SDO_ABORT, d->node, steps[d->sdo_step].index,
             now_us);
        return;
    }
    if (s->type !=
        (steps[d->sdo_step].write ? QRTCAN_SDO_WRITE_OK : QRTCAN_SDO_READ_OK)) {
        m->frames_malformed++;
        return;
    }
    if (steps == bringup && steps[d->sdo_step].check &&
        sized(s->data, steps[d->sdo_step].size) !=
            sized(bringup_value(m, d->sdo_step), steps[d->sdo_step].size)) {
        fail(m, QRTCAN_REASON_SDO_ABORT, d->node, steps[d->sdo_step].index,
             now_us);
        return;
    }
    if (steps == bringup && s->index == OD_POSITION_ACTUAL) {
        d->position_counts = (int32_t)s->data;
        d->target_counts = d->position_counts;
        d->tpdo_seen = 1;
    }
    d->sdo_waiting = 0;
    d->sdo_attempt = 0;
    d->sdo_step++;
}

/* --- the cycle -----------------------------------------------------------*/

static int all_enabled(const struct qrtcan_master *m)
{
    int j;
    for (j = 0; j < QRTCAN_JOINTS; j++)
        if (qrtcan_402_state_from_statusword(m->drive[j].statusword) !=
            QRTCAN_402_OPERATION_ENABLED)
            return 0;
    return 1;
}

static void start_segment(struct qrtcan_master *m, uint64_t now_us)
{
    double d[3];
    int j;
    if (!segment_targets(m, d, m->segment_counts)) {
        fail(m, QRTCAN_REASON_SDO_ABORT, 0, OD_POSITION_ACTUAL, now_us);
        return;
    }
    /* the synchronised trapezoid (qrtcan/profile.h), in the drives' counts */
    if (qrtcan_segment_drive_profile(
            m->cfg.max_speed_deg_s, m->cfg.max_accel_deg_s2, m->cfg.scale, d,
            m->segment_profile[0], m->segment_profile[1]) != QRTCAN_OK) {
        fail(m, QRTCAN_REASON_SDO_ABORT, 0, OD_PROFILE_VELOCITY, now_us);
        return;
    }
    for (j = 0; j < QRTCAN_JOINTS; j++) {
        m->segment_profile[2][j] = m->segment_profile[1][j];
        m->drive[j].sdo_step = 0;
        m->drive[j].sdo_attempt = 0;
        m->drive[j].sdo_waiting = 0;
    }
    m->segment_phase = 0;
}

static void finish_path(struct qrtcan_master *m, uint64_t now_us)
{
    m->path_done = 1;
    m->n_waypoints = 0;
    enter(m, QRTCAN_MASTER_READY, now_us);
}

static void step_path(struct qrtcan_master *m, uint64_t now_us)
{
    int j;
    if (m->segment_phase == 0) {
        if (!run_sdo(m, profile, PROFILE_STEPS,
                     (const uint32_t(*)[QRTCAN_JOINTS])m->segment_profile,
                     now_us))
            return;
        /* profiles set: the new set-point, to all three at once */
        for (j = 0; j < QRTCAN_JOINTS; j++) {
            m->drive[j].target_counts = m->segment_counts[j];
            m->drive[j].controlword = CW_ENABLED | QRTCAN_CW_NEW_SETPOINT;
        }
        send_all_rpdos(m);
        m->segment_phase = 1;
    } else if (m->segment_phase == 1) {
        if (!all_bits(m, QRTCAN_SW_SETPOINT_ACK, 1))
            return;
        for (j = 0; j < QRTCAN_JOINTS; j++)
            m->drive[j].controlword = CW_ENABLED;
        send_all_rpdos(m);
        m->segment_phase = 2;
    } else if (m->segment_phase == 2) {
        if (!all_bits(m, QRTCAN_SW_SETPOINT_ACK, 0) ||
            !all_bits(m, QRTCAN_SW_TARGET_REACHED, 1))
            return;
        if (++m->waypoint >= m->n_waypoints) {
            finish_path(m, now_us);
            return;
        }
        start_segment(m, now_us);
    }
}

static void supervise(struct qrtcan_master *m, uint64_t now_us)
{
    int j;
    for (j = 0; j < QRTCAN_JOINTS; j++) {
        const struct qrtcan_drive *d = &m->drive[j];
        enum qrtcan_402_state st;
        if (d->heartbeat_seen &&
            now_us - d->last_heartbeat_us > m->cfg.heartbeat_timeout_us) {
            fail(m, QRTCAN_REASON_HEARTBEAT_LOST, d->node, 0, now_us);
            return;
        }
        if (m->state != QRTCAN_MASTER_READY &&
            m->state != QRTCAN_MASTER_MOVING &&
            m->state != QRTCAN_MASTER_STOPPED)
            continue;
        st = qrtcan_402_state_from_statusword(d->statusword);
        if (st == QRTCAN_402_FAULT || st == QRTCAN_402_FAULT_REACTION_ACTIVE) {
            fail(m, QRTCAN_REASON_DRIVE_FAULT, d->node, d->last_emcy, now_us);
            return;
        }
    }
}

void qrtcan_master_tick(struct qrtcan_master *m, uint64_t now_us)
{
    struct qrtcan_frame f;
    int j;
    if (m->state == QRTCAN_MASTER_OFF && !m->started)
        return;
    /* our heartbeat feeds the drives' heartbeat consumers, the SYNC their
     * SYNC watchdogs; a stalled host stops the heartbeat alone, so that
     * the drives stop by themselves while their positions are still read */
    if (m->host_alive &&
        now_us - m->last_heartbeat_us >= m->cfg.master_heartbeat_us)
        push_heartbeat(m, now_us);
    if (now_us - m->last_sync_us >= m->cfg.sync_period_us) {
        m->last_sync_us = now_us;
        if (qrtcan_sync_encode(0, &f) == QRTCAN_OK)
            push(m, &f);
        m->sync_answers = 0;
        if (m->state != QRTCAN_MASTER_STARTING && m->state != QRTCAN_MASTER_OFF)
            send_all_rpdos(m);
    }
    supervise(m, now_us);
    switch (m->state) {
    case QRTCAN_MASTER_OFF:
    case QRTCAN_MASTER_READY:
        break;
    case QRTCAN_MASTER_STOPPED:
        for (j = 0; j < QRTCAN_JOINTS; j++)
            m->drive[j].controlword = QRTCAN_CW_CMD_QUICK_STOP;
        break;
    case QRTCAN_MASTER_FAULT:
        if (m->started && m->host_alive &&
            now_us - m->state_since_us >= m->cfg.retry_after_us) {
            m->recoveries++;
            begin_bringup(m, now_us);
        }
        break;
    case QRTCAN_MASTER_STARTING:
        if (run_sdo(m, bringup, BRINGUP_STEPS, NULL, now_us)) {
            /* a drive's consumer watches from our first heartbeat after
             * 0x1016 was written: one now, ahead of NMT start, so that no
             * drive is enabled unwatched */
            push_heartbeat(m, now_us);
            for (j = 0; j < QRTCAN_JOINTS; j++) {
                if (qrtcan_nmt_encode(QRTCAN_NMT_START, m->drive[j].node, &f) ==
                    QRTCAN_OK)
                    push(m, &f);
                m->drive[j].controlword = 0;
            }
            m->segment_phase = -1;
            enter(m, QRTCAN_MASTER_ENABLING, now_us);
        }
        break;
    case QRTCAN_MASTER_ENABLING:
        if (all_enabled(m)) {
            for (j = 0; j < QRTCAN_JOINTS; j++)
                m->drive[j].controlword = CW_ENABLED;
            if (m->n_waypoints > 0) {
                enter(m, QRTCAN_MASTER_MOVING, now_us);
                m->waypoint = 1; /* waypoint 0 is where the arm is */
                if (m->waypoint >= m->n_waypoints)
                    finish_path(m, now_us);
                else
                    start_segment(m, now_us);
            } else {
                enter(m, QRTCAN_MASTER_READY, now_us);
            }
            break;
        }
        if (now_us - m->state_since_us > m->cfg.enable_timeout_us) {
            fail(m, QRTCAN_REASON_ENABLE_TIMEOUT, 0, 0, now_us);
            break;
        }
        for (j = 0; j < QRTCAN_JOINTS; j++) {
            struct qrtcan_drive *d = &m->drive[j];
            enum qrtcan_402_state st =
                qrtcan_402_state_from_statusword(d->statusword);
            /* from Quick Stop Active straight back (transition 16): going
             * round through Switch On Disabled would drop the torque that
             * holds the arm up */
            uint16_t cw =
                st == QRTCAN_402_QUICK_STOP_ACTIVE
                    ? (uint16_t)CW_ENABLED
                    : qrtcan_402_controlword_toward(
                          st, QRTCAN_402_OPERATION_ENABLED, d->controlword);
            if (cw != d->controlword) {
                d->controlword = cw;
                d->target_counts = d->position_counts; /* hold */
                send_rpdo(m, j, 0);
            }
        }
        break;
    case QRTCAN_MASTER_MOVING:
        step_path(m, now_us);
        break;
    }
}

/* --- received frames -----------------------------------------------------*/

static int drive_index(const struct qrtcan_master *m, unsigned node)
{
    int j;
    for (j = 0; j < QRTCAN_JOINTS; j++)
        if (m->drive[j].node == node)
            return j;
    return -1;
}

int qrtcan_master_on_frame(struct qrtcan_master *m,
                           const struct qrtcan_frame *f, uint64_t now_us)
{
    enum qrtcan_kind kind;
    unsigned node;
    int rc = qrtcan_classify(f, &kind, &node), j;
    m->frames_in++;
    if (rc != QRTCAN_OK) {
        m->frames_ignored++;
        return QRTCAN_E_ID;
    }
    j = drive_index(m, node);
    if (j < 0 || kind == QRTCAN_KIND_NMT || kind == QRTCAN_KIND_SYNC ||
        kind == QRTCAN_KIND_RPDO1 || kind == QRTCAN_KIND_RSDO) {
        m->frames_ignored++; /* not from one of our drives */
        return QRTCAN_E_ID;
    }
    switch (kind) {
    case QRTCAN_KIND_TPDO1: {
        struct qrtcan_402_tpdo p;
        rc = qrtcan_402_tpdo_decode(f, &node, &p);
        if (rc != QRTCAN_OK)
            break;
        m->drive[j].statusword = p.statusword;
        m->drive[j].position_counts = p.position_actual;
        m->drive[j].tpdo_seen = 1;
        m->sync_counts[j] = p.position_actual;
        m->sync_answers |= 1u << j;
        if (m->sync_answers == (1u << QRTCAN_JOINTS) - 1u) {
            memcpy(m->coherent_counts, m->sync_counts,
                   sizeof m->coherent_counts);
            m->coherent = 1;
        }
        return QRTCAN_OK;
    }
    case QRTCAN_KIND_TSDO: {
        struct qrtcan_sdo s;
        rc = qrtcan_sdo_decode_response(f, &node, &s);
        if (rc != QRTCAN_OK)
            break;
        sdo_answer(m, j, &s, now_us);
        return QRTCAN_OK;
    }
    case QRTCAN_KIND_HEARTBEAT: {
        enum qrtcan_nmt_state st;
        rc = qrtcan_heartbeat_decode(f, &node, &st);
        if (rc != QRTCAN_OK)
            break;
        /* a boot-up message after bring-up: the drive restarted and lost
         * its configuration */
        if (st == QRTCAN_NMT_BOOTUP && m->state != QRTCAN_MASTER_STARTING &&
            m->state != QRTCAN_MASTER_OFF)
            fail(m, QRTCAN_REASON_DRIVE_FAULT, node, 0, now_us);
        m->drive[j].heartbeat_seen = 1;
        m->drive[j].last_heartbeat_us = now_us;
        m->drive[j].nmt_state = (int)st;
        return QRTCAN_OK;
    }
    case QRTCAN_KIND_EMCY: {
        struct qrtcan_emcy e;
        rc = qrtcan_emcy_decode(f, &node, &e);
        if (rc != QRTCAN_OK)
            break;
        m->drive[j].last_emcy = e.code;
        /* a heartbeat event while the host watchdog holds our heartbeat
         * back is the stop we asked for, not a drive fault */
        if (e.code != QRTCAN_EMCY_NO_ERROR &&
            (m->host_alive || e.code != QRTCAN_EMCY_HEARTBEAT) &&
            (m->state == QRTCAN_MASTER_READY ||
             m->state == QRTCAN_MASTER_MOVING ||
             m->state == QRTCAN_MASTER_STOPPED))
            fail(m, QRTCAN_REASON_DRIVE_FAULT, node, e.code, now_us);
        return QRTCAN_OK;
    }
    default:
        rc = QRTCAN_E_ID;
        break;
    }
    m->frames_malformed++;
    return rc;
}

/* --- status --------------------------------------------------------------*/

void qrtcan_master_get_status(const struct qrtcan_master *m,
                              struct qrtcan_master_status *st)
{
    int j;
    memset(st, 0, sizeof *st);
    st->state = m->state;
    st->reason = m->reason;
    st->reason_node = m->reason_node;
    st->reason_code = m->reason_code;
    st->all_positions_known = 1;
    for (j = 0; j < QRTCAN_JOINTS; j++) {
        st->joints_deg[j] = joint_deg(m, j);
        if (m->coherent)
            qrtcan_counts_to_deg(&m->cfg.scale[j], m->coherent_counts[j],
                                 &st->joints_deg[j]);
        st->statusword[j] = m->drive[j].statusword;
        st->drive_state[j] =
            qrtcan_402_state_from_statusword(m->drive[j].statusword);
        st->all_positions_known &= m->drive[j].tpdo_seen;
    }
    st->joints_deg[0] = qrt_wrap_deg(st->joints_deg[0]);
    st->waypoint = m->waypoint;
    st->n_waypoints = m->n_waypoints;
    st->path_done = m->path_done;
    st->frames_in = m->frames_in;
    st->frames_ignored = m->frames_ignored;
    st->frames_malformed = m->frames_malformed;
    st->frames_out = m->frames_out;
    st->frames_dropped = m->frames_dropped;
    st->frames_withdrawn = m->frames_withdrawn;
    st->recoveries = m->recoveries;
    st->host_alive = m->host_alive;
    st->heartbeat_produced =
        m->host_alive && (m->state != QRTCAN_MASTER_OFF || m->started);
}

const char *qrtcan_master_state_name(enum qrtcan_master_state s)
{
    switch (s) {
    case QRTCAN_MASTER_OFF:
        return "off";
    case QRTCAN_MASTER_STARTING:
        return "starting";
    case QRTCAN_MASTER_ENABLING:
        return "enabling";
    case QRTCAN_MASTER_READY:
        return "ready";
    case QRTCAN_MASTER_MOVING:
        return "moving";
    case QRTCAN_MASTER_STOPPED:
        return "stopped";
    case QRTCAN_MASTER_FAULT:
        return "fault";
    }
    return "unknown";
}

const char *qrtcan_master_reason_name(enum qrtcan_master_reason r)
{
    switch (r) {
    case QRTCAN_REASON_NONE:
        return "none";
    case QRTCAN_REASON_COMMANDED:
        return "quick stop commanded";
    case QRTCAN_REASON_DRIVE_FAULT:
        return "drive fault";
    case QRTCAN_REASON_HEARTBEAT_LOST:
        return "drive heartbeat lost";
    case QRTCAN_REASON_SDO_TIMEOUT:
        return "drive did not answer an SDO";
    case QRTCAN_REASON_SDO_ABORT:
        return "drive refused its configuration";
    case QRTCAN_REASON_ENABLE_TIMEOUT:
        return "drives not enabled in time";
    case QRTCAN_REASON_BUS:
        return "CAN bus error";
    case QRTCAN_REASON_SHUTDOWN:
        return "shut down";
    case QRTCAN_REASON_HOST_WATCHDOG:
        return "host watchdog: a guarding thread stalled";
    }
    return "unknown";
}
