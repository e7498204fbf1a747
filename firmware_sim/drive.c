#include "drive.h"

#include <stddef.h>
#include <string.h>

#include "qrtcan/emcy.h"
#include "qrtcan/sdo.h"
#include "qrtcan/sync.h"

/* Defaults of the profile objects: 90 deg/s and 180 deg/s^2 at the
 * 1000 counts/deg the project's scale uses by default. */
#define DEFAULT_VELOCITY 90000u
#define DEFAULT_ACCEL 180000u
#define DEFAULT_QUICK_STOP_DECEL 720000u
#define DEFAULT_WINDOW 10u
#define VENDOR_ID 0x00000051u /* not a registered vendor: a simulator */
#define PRODUCT_CODE 0x00000402u

enum { RO = 1, RW = 2 };

struct od_entry {
    uint16_t index;
    uint8_t subindex;
    uint8_t size; /* bytes */
    uint8_t access;
    uint16_t offset; /* of the value in struct drive */
};

/* An entry: the field's size from a compound literal that sizeof never
 * evaluates (no null pointer cast). `field` is a member designator, which
 * cannot take the parentheses MISRA C:2012 rule 20.7 asks for. */
/* cppcheck-suppress misra-c2012-20.7 */
#define E(i, s, field, acc)                                                    \
    {                                                                          \
        (i), (s), (uint8_t)sizeof(((struct drive){.nmt = 0}).field), (acc),    \
            (uint16_t)offsetof(struct drive, field)                            \
    }

/* The object dictionary as data (CANopenNode's way): sorted by index and
 * subindex, so the EDS (can/servo_sim.eds) can be checked against it. */
static const struct od_entry od[] = {
    E(0x1000, 0, device_type, RO),
    E(0x1001, 0, error_register, RO),
    E(0x1016, 0, hb_consumer_count, RO),
    E(0x1016, 1, hb_consumer[0], RW),
    E(0x1016, 2, hb_consumer[1], RW),
    E(0x1016, 3, hb_consumer[2], RW),
    E(0x1016, 4, hb_consumer[3], RW),
    E(0x1017, 0, heartbeat_ms, RW),
    E(0x1018, 0, identity_count, RO),
    E(0x1018, 1, identity[0], RO),
    E(0x1018, 2, identity[1], RO),
    E(0x1018, 3, identity[2], RO),
    E(0x1018, 4, identity[3], RO),
    E(0x1400, 0, pdo_comm_count, RO),
    E(0x1400, 1, rpdo_cob_id, RO),
    E(0x1400, 2, rpdo_type, RO),
    E(0x1600, 0, pdo_map_count, RO),
    E(0x1600, 1, rpdo_map[0], RO),
    E(0x1600, 2, rpdo_map[1], RO),
    E(0x1800, 0, pdo_comm_count, RO),
    E(0x1800, 1, tpdo_cob_id, RO),
    E(0x1800, 2, tpdo_type, RO),
    E(0x1A00, 0, pdo_map_count, RO),
    E(0x1A00, 1, tpdo_map[0], RO),
    E(0x1A00, 2, tpdo_map[1], RO),
    E(0x2000, 0, watchdog_ms, RW),
    E(0x2001, 0, servo_error, RW),
    E(0x6007, 0, abort_option, RW),
    E(0x603F, 0, error_code, RO),
    E(0x6040, 0, controlword, RW),
    E(0x6041, 0, statusword, RO),
    E(0x6060, 0, mode, RW),
    E(0x6061, 0, mode_display, RO),
    E(0x6064, 0, position_actual, RO),
    E(0x6067, 0, position_window, RW),
    E(0x606C, 0, velocity_actual, RO),
    E(0x607A, 0, target, RW),
    E(0x607D, 0, limit_count, RO),
    E(0x607D, 1, limit[0], RW),
    E(0x607D, 2, limit[1], RW),
    E(0x6081, 0, profile_velocity, RW),
    E(0x6083, 0, profile_accel, RW),
    E(0x6084, 0, profile_decel, RW),
    E(0x6085, 0, quick_stop_decel, RW),
    E(0x6502, 0, supported_modes, RO),
};

static uint64_t now(const struct can_driver *can)
{
    return can->now_us(can->ctx);
}

static void send(struct drive *d, const struct can_driver *can,
                 const struct qrtcan_frame *f)
{
    if (!d->muted) {
        (void)can->send(can->ctx, f); /* a full bus drops it, as on a wire */
    }
}

static void send_emcy(struct drive *d, const struct can_driver *can,
                      uint16_t code)
{
    struct qrtcan_frame f;
    struct qrtcan_emcy e;
    memset(&e, 0, sizeof e);
    e.code = code;
    e.error_register = d->error_register;
    e.vendor[0] = (uint8_t)d->state;
    if (qrtcan_emcy_encode(d->cfg.node, &e, &f) == QRTCAN_OK) {
        send(d, can, &f);
    }
}

static int32_t round_counts(double x)
{
    return x >= 0 ? (int32_t)(x + 0.5) : (int32_t)(x - 0.5);
}

static void update_statusword(struct drive *d)
{
    uint16_t sw = qrtcan_402_statusword_bits(d->state) | QRTCAN_SW_REMOTE;
    int reached;
    if (d->state == QRTCAN_402_OPERATION_ENABLED) {
        reached =
            (d->controlword & QRTCAN_CW_HALT) ? d->vel == 0.0 : !d->moving;
    } else {
        reached = d->vel == 0.0;
    }
    if (reached) {
        sw |= QRTCAN_SW_TARGET_REACHED;
    }
    if (d->limit_active) {
        sw |= QRTCAN_SW_INTERNAL_LIMIT;
    }
    if (d->setpoint_ack) {
        sw |= QRTCAN_SW_SETPOINT_ACK;
    }
    if (d->error_register != 0) {
        sw |= QRTCAN_SW_WARNING;
    }
    d->statusword = sw;
    d->position_actual = round_counts(d->pos);
    d->velocity_actual = round_counts(d->vel);
    d->mode_display = d->mode;
}

static void reset_application(struct drive *d)
{
    d->state = QRTCAN_402_SWITCH_ON_DISABLED; /* 0 and 1 are automatic */
    d->vel = 0;
    d->moving = 0;
    d->limit_active = 0;
    d->setpoint_ack = 0;
    d->device_type = 0x00020192u; /* CiA 402, servo drive */
    d->identity_count = 4;
    d->identity[0] = VENDOR_ID;
    d->identity[1] = PRODUCT_CODE;
    d->identity[2] = 0x00010000u;
    d->identity[3] = d->cfg.node;
    d->watchdog_ms = d->cfg.watchdog_ms;
    d->servo_error = d->cfg.servo_error;
    d->error_code = 0;
    d->error_register = 0;
    d->controlword = 0;
    /* quick stop: a drive that lost its master keeps the arm (which has no
     * brakes) under torque at rest, where 1 (fault) or 2 (disable voltage)
     * would drop it; the master writes 0x6007 at bring-up anyway and reads
     * it back, so it relies on no default */
    d->abort_option = 3;
    d->mode = QRTCAN_MODE_PROFILE_POSITION;
    d->position_window = DEFAULT_WINDOW;
    d->target = round_counts(d->pos);
    d->setpoint = d->target;
    d->limit_count = 2;
    d->limit[0] = d->cfg.limit_min;
    d->limit[1] = d->cfg.limit_max;
    d->profile_velocity = DEFAULT_VELOCITY;
    d->profile_accel = DEFAULT_ACCEL;
    d->profile_decel = DEFAULT_ACCEL;
    d->quick_stop_decel = DEFAULT_QUICK_STOP_DECEL;
    d->supported_modes = 1u; /* profile position only */
}

static void reset_communication(struct drive *d, const struct can_driver *can)
{
    struct qrtcan_frame f;
    unsigned n = d->cfg.node, i;
    d->heartbeat_ms = d->cfg.heartbeat_ms;
    d->pdo_comm_count = 2;
    d->pdo_map_count = 2;
    d->rpdo_cob_id = qrtcan_cob_id(QRTCAN_FN_RPDO1, n);
    d->tpdo_cob_id = qrtcan_cob_id(QRTCAN_FN_TPDO1, n);
    d->rpdo_type = 255; /* acted on when received */
    d->tpdo_type = 1;   /* sent after every SYNC */
    d->rpdo_map[0] = 0x60400010u;
    d->rpdo_map[1] = 0x607A0020u;
    d->tpdo_map[0] = 0x60410010u;
    d->tpdo_map[1] = 0x60640020u;
    d->last_sync_us = 0;
    d->watchdog_tripped = 0;
    /* no heartbeat consumer at power-up, as on real drives: 0x1016 is a
     * communication object, so reset communication clears it too */
    d->hb_consumer_count = (uint8_t)DRIVE_HB_CONSUMERS;
    for (i = 0; i < DRIVE_HB_CONSUMERS; i++) {
        d->hb_consumer[i] = 0;
        d->hb_watch[i] = (uint8_t)DRIVE_HB_IDLE;
        d->hb_seen_us[i] = 0;
    }
    if (qrtcan_heartbeat_encode(n, QRTCAN_NMT_BOOTUP, &f) == QRTCAN_OK) {
        send(d, can, &f);
    }
    d->nmt = QRTCAN_NMT_PRE_OP;
    d->next_heartbeat_us = now(can) + (uint64_t)d->heartbeat_ms * 1000u;
    update_statusword(d);
}

void drive_init(struct drive *d, const struct drive_config *cfg,
                const struct can_driver *can)
{
    memset(d, 0, sizeof *d);
    d->cfg = *cfg;
    d->pos = cfg->start_position;
    d->last_tick_us = now(can);
    reset_application(d);
    reset_communication(d, can);
}

static void enter_fault(struct drive *d, uint16_t code, uint8_t reg,
                        const struct can_driver *can)
{
    d->error_code = code;
    d->error_register |= reg | QRTCAN_ERRREG_GENERIC;
    d->moving = 0;
    d->state = QRTCAN_402_FAULT_REACTION_ACTIVE;
    update_statusword(d);
    send_emcy(d, can, code);
}

void drive_fault(struct drive *d, uint16_t code, const struct can_driver *can)
{
    if (d->state == QRTCAN_402_FAULT ||
        d->state == QRTCAN_402_FAULT_REACTION_ACTIVE) {
        return;
    }
    enter_fault(d, code, QRTCAN_ERRREG_CURRENT, can);
}

/* A new controlword, from RPDO1 or SDO: state machine, then the profile
 * position handshake (new setpoint on the rising edge of bit 4). */
static void apply_controlword(struct drive *d, uint16_t cw,
                              const struct can_driver *can)
{
    uint16_t prev = d->controlword;
    enum qrtcan_402_cmd cmd = qrtcan_402_command(prev, cw);
    enum qrtcan_402_state before = d->state, after;
    after = qrtcan_402_transition(before, cmd);
    d->controlword = cw;
    if (after != before) {
        d->state = after;
        if (before == QRTCAN_402_FAULT) {
            d->error_code = 0;
            d->error_register = 0;
            send_emcy(d, can, QRTCAN_EMCY_NO_ERROR);
        }
        if (after == QRTCAN_402_OPERATION_ENABLED) {
            /* hold where the motor is; only a new setpoint moves it */
            d->setpoint = round_counts(d->pos) - d->servo_error;
            d->moving = 0;
            d->limit_active = 0;
        }
        if (after == QRTCAN_402_SWITCH_ON_DISABLED ||
            after == QRTCAN_402_READY_TO_SWITCH_ON ||
            after == QRTCAN_402_SWITCHED_ON) {
            d->vel = 0; /* power stage off: the motor stops where it is */
            d->moving = 0;
        }
    }
    if (d->state == QRTCAN_402_OPERATION_ENABLED &&
        d->mode == QRTCAN_MODE_PROFILE_POSITION) {
        if ((cw & QRTCAN_CW_NEW_SETPOINT) && !(prev & QRTCAN_CW_NEW_SETPOINT)) {
            /* change-set-immediately (bit 5) is always assumed: the
             * simulator keeps no setpoint queue */
            int64_t t = d->target;
            if (cw & QRTCAN_CW_RELATIVE) {
                t += d->setpoint;
            }
            d->limit_active = 0;
            if (t < d->limit[0]) {
                t = d->limit[0];
                d->limit_active = 1;
            }
            if (t > d->limit[1]) {
                t = d->limit[1];
                d->limit_active = 1;
            }
            d->setpoint = (int32_t)t;
            d->moving = 1;
            d->setpoint_ack = 1;
        }
    }
    if (!(cw & QRTCAN_CW_NEW_SETPOINT)) {
        d->setpoint_ack = 0;
    }
    update_statusword(d);
}

static const struct od_entry *od_find(uint16_t index, uint8_t sub,
                                      uint32_t *abort_code)
{
    size_t i;
    int index_seen = 0;
    for (i = 0; i < sizeof od / sizeof od[0]; i++) {
        if (od[i].index == index) {
            index_seen = 1;
            if (od[i].subindex == sub) {
                return &od[i];
            }
        }
    }
    *abort_code =
        index_seen ? QRTCAN_SDO_ABORT_NO_SUBINDEX : QRTCAN_SDO_ABORT_NO_OBJECT;
    return 0;
}

static uint32_t od_get(const struct drive *d, const struct od_entry *e)
{
    const unsigned char *p = (const unsigned char *)d + e->offset;
    switch (e->size) {
    case 1:
        return *(const uint8_t *)p;
    case 2:
        return *(const uint16_t *)(const void *)p;
    default:
        return *(const uint32_t *)(const void *)p;
    }
}

static void od_set(struct drive *d, const struct od_entry *e, uint32_t v)
{
    unsigned char *p = (unsigned char *)d + e->offset;
    switch (e->size) {
    case 1:
        *(uint8_t *)p = (uint8_t)v;
        break;
    case 2:
        *(uint16_t *)(void *)p = (uint16_t)v;
        break;
    default:
        *(uint32_t *)(void *)p = v;
        break;
    }
}

/* A heartbeat consumer entry (0x1016:n) is used iff it names a node
 * (1..127) and a time (not 0); CiA 301. */
static unsigned hb_entry_node(uint32_t entry)
{
    return (unsigned)((entry >> 16) & 0xFFu);
}

static int hb_entry_used(uint32_t entry)
{
    unsigned node = hb_entry_node(entry);
    return node >= 1u && node <= 127u && (entry & 0xFFFFu) != 0u;
}

/* Entry sub of 0x1016 may take v: bits 31..24 are reserved (0), and two
 * used entries never watch the same node (CiA 301 refuses that with
 * "general parameter incompatibility"). Rewriting an entry's own node is
 * fine. */
static uint32_t hb_entry_check(const struct drive *d, uint8_t sub, uint32_t v)
{
    unsigned i;
    if ((v & 0xFF000000u) != 0u) {
        return QRTCAN_SDO_ABORT_VALUE;
    }
    if (!hb_entry_used(v)) {
        return 0;
    }
    for (i = 0; i < DRIVE_HB_CONSUMERS; i++) {
        if (i + 1u != (unsigned)sub && hb_entry_used(d->hb_consumer[i]) &&
            hb_entry_node(d->hb_consumer[i]) == hb_entry_node(v)) {
            return QRTCAN_SDO_ABORT_INCOMPATIBLE;
        }
    }
    return 0;
}

/* Values the drive refuses (0 = accepted). */
static uint32_t od_check(const struct drive *d, const struct od_entry *e,
                         int32_t sv, uint32_t v)
{
    switch (e->index) {
    case 0x1016:
        return hb_entry_check(d, e->subindex, v);
    case 0x6060:
        return sv == QRTCAN_MODE_PROFILE_POSITION ? 0 : QRTCAN_SDO_ABORT_VALUE;
    case 0x6007:
        /* 0 no action, 1 fault, 2 disable voltage, 3 quick stop */
        return sv >= 0 && sv <= 3 ? 0 : QRTCAN_SDO_ABORT_VALUE;
    case 0x6081:
    case 0x6083:
    case 0x6084:
    case 0x6085:
        return v == 0 ? QRTCAN_SDO_ABORT_TOO_LOW
                      : (v > 100000000u ? QRTCAN_SDO_ABORT_TOO_HIGH : 0);
    case 0x607D:
        if (e->subindex == 1 && sv > d->limit[1]) {
            return QRTCAN_SDO_ABORT_TOO_HIGH;
        }
        return e->subindex == 2 && sv < d->limit[0] ? QRTCAN_SDO_ABORT_TOO_LOW
                                                    : 0;
    default:
        return 0;
    }
}

static void sdo_server(struct drive *d, const struct qrtcan_frame *f,
                       const struct can_driver *can)
{
    struct qrtcan_sdo req, ans;
    struct qrtcan_frame out;
    const struct od_entry *e;
    unsigned node;
    uint32_t abort_code = 0;
    int rc = qrtcan_sdo_decode_request(f, &node, &req);
    if (rc == QRTCAN_E_ID || rc == QRTCAN_E_DLC || node != d->cfg.node) {
        return; /* not an SDO request for us */
    }
    memset(&ans, 0, sizeof ans);
    ans.index = req.index;
    ans.subindex = req.subindex;
    if (rc != QRTCAN_OK) {
        abort_code = QRTCAN_SDO_ABORT_CMD;
    } else if (req.type == QRTCAN_SDO_ABORT) {
        return; /* nothing in progress to abort: transfers are one frame */
    } else if ((e = od_find(req.index, req.subindex, &abort_code)) != NULL) {
        if (req.type == QRTCAN_SDO_READ) {
            ans.type = QRTCAN_SDO_READ_OK;
            ans.size = e->size;
            ans.data = od_get(d, e);
        } else if (e->access == RO) {
            abort_code = QRTCAN_SDO_ABORT_READ_ONLY;
        } else if (req.size != 0 && req.size != e->size) {
            abort_code = QRTCAN_SDO_ABORT_LENGTH;
        } else {
            struct qrtcan_sdo sized = req;
            sized.size = e->size;
            abort_code = od_check(d, e, qrtcan_sdo_signed(&sized), req.data);
            if (abort_code == 0) {
                ans.type = QRTCAN_SDO_WRITE_OK;
                if (e->index == 0x6040) {
                    apply_controlword(d, (uint16_t)req.data, can);
                } else {
                    od_set(d, e, req.data);
                }
                if (e->index == 0x1016) {
                    /* a written entry watches from its node's next
                     * heartbeat on, not from an older one */
                    d->hb_watch[e->subindex - 1u] = (uint8_t)DRIVE_HB_IDLE;
                }
            }
        }
    }
    if (abort_code != 0) {
        ans.type = QRTCAN_SDO_ABORT;
        ans.data = abort_code;
    }
    if (qrtcan_sdo_encode_response(d->cfg.node, &ans, &out) == QRTCAN_OK) {
        send(d, can, &out);
    }
}

static void nmt_command(struct drive *d, const struct qrtcan_frame *f,
                        const struct can_driver *can)
{
    enum qrtcan_nmt_cmd cmd;
    unsigned target;
    if (qrtcan_nmt_decode(f, &cmd, &target) != QRTCAN_OK ||
        !qrtcan_nmt_addressed_to(target, d->cfg.node)) {
        return;
    }
    switch (cmd) {
    case QRTCAN_NMT_START:
        if (d->nmt != QRTCAN_NMT_OPERATIONAL) {
            d->last_sync_us = 0; /* the watchdog arms on the next SYNC */
            d->watchdog_tripped = 0;
        }
        d->nmt = QRTCAN_NMT_OPERATIONAL;
        break;
    case QRTCAN_NMT_STOP:
        d->nmt = QRTCAN_NMT_STOPPED;
        break;
    case QRTCAN_NMT_PRE_OPERATIONAL:
        d->nmt = QRTCAN_NMT_PRE_OP;
        break;
    case QRTCAN_NMT_RESET_NODE:
        reset_application(d);
        reset_communication(d, can);
        break;
    case QRTCAN_NMT_RESET_COMM:
        reset_communication(d, can);
        break;
    }
}

static void sync_seen(struct drive *d, const struct can_driver *can)
{
    d->last_sync_us = now(can);
    d->watchdog_tripped = 0;
}

/* A heartbeat of node (not this drive): it feeds the consumer entries that
 * watch that node and only those; it arms an entry that was written since
 * the last one, and re-arms one whose event fired. */
static void heartbeat_seen(struct drive *d, unsigned node, uint64_t t)
{
    unsigned i;
    for (i = 0; i < DRIVE_HB_CONSUMERS; i++) {
        if (hb_entry_used(d->hb_consumer[i]) &&
            hb_entry_node(d->hb_consumer[i]) == node) {
            d->hb_watch[i] = (uint8_t)DRIVE_HB_ARMED;
            d->hb_seen_us[i] = t;
        }
    }
}

void drive_on_frame(struct drive *d, const struct qrtcan_frame *f,
                    const struct can_driver *can)
{
    enum qrtcan_kind kind;
    unsigned node, counter;
    struct qrtcan_frame out;
    if (d->muted || qrtcan_classify(f, &kind, &node) != QRTCAN_OK) {
        return;
    }
    switch (kind) {
    case QRTCAN_KIND_NMT:
        nmt_command(d, f, can);
        break;
    case QRTCAN_KIND_SYNC:
        if (qrtcan_sync_decode(f, &counter) != QRTCAN_OK ||
            d->nmt != QRTCAN_NMT_OPERATIONAL) {
            break;
        }
        sync_seen(d, can);
        {
            struct qrtcan_402_tpdo t;
            update_statusword(d);
            t.statusword = d->statusword;
            t.position_actual = d->position_actual;
            if (qrtcan_402_tpdo_encode(d->cfg.node, &t, &out) == QRTCAN_OK) {
                send(d, can, &out);
            }
        }
        break;
    case QRTCAN_KIND_HEARTBEAT: {
        enum qrtcan_nmt_state st;
        if (qrtcan_heartbeat_decode(f, &node, &st) == QRTCAN_OK &&
            node != d->cfg.node) {
            heartbeat_seen(d, node, now(can));
        }
        break;
    }
    case QRTCAN_KIND_RPDO1: {
        struct qrtcan_402_rpdo r;
        if (node != d->cfg.node || d->nmt != QRTCAN_NMT_OPERATIONAL ||
            qrtcan_402_rpdo_decode(f, &node, &r) != QRTCAN_OK) {
            break;
        }
        d->target = r.target_position;
        apply_controlword(d, r.controlword, can);
        break;
    }
    case QRTCAN_KIND_RSDO:
        if (node == d->cfg.node &&
            (d->nmt == QRTCAN_NMT_PRE_OP || d->nmt == QRTCAN_NMT_OPERATIONAL)) {
            sdo_server(d, f, can);
        }
        break;
    default:
        break;
    }
}

/* Speed towards zero at decel over dt; position follows. */
static void brake(struct drive *d, double decel, double dt)
{
    double speed = d->vel < 0 ? -d->vel : d->vel;
    double dir = d->vel < 0 ? -1.0 : 1.0;
    double slower = speed - decel * dt;
    if (slower <= 0) {
        d->pos += dir * speed * speed / (2 * decel);
        d->vel = 0;
        return;
    }
    d->pos += dir * 0.5 * (speed + slower) * dt;
    d->vel = dir * slower;
}

/* The trapezoid, one step: accelerate to the profile velocity, cruise,
 * brake so as to stop at the goal; lands exactly on it. */
static void profile_step(struct drive *d, double dt)
{
    double goal = (double)d->setpoint + (double)d->servo_error;
    double dist = goal - d->pos;
    double dir = dist < 0 ? -1.0 : 1.0;
    double left = dist * dir;
    double speed = d->vel * dir; /* along the way to the goal */
    double acc = d->profile_accel, dec = d->profile_decel;
    double vmax = d->profile_velocity, step;
    if (speed < 0) { /* moving away (target changed): brake first */
        brake(d, dec, dt);
        return;
    }
    if (speed * speed / (2 * dec) >= left) {
        speed -= dec * dt;
        if (speed < dec * dt) {
            speed = dec * dt; /* creep the last counts in */
        }
    } else {
        speed += acc * dt;
        if (speed > vmax) {
            speed = vmax;
        }
    }
    step = speed * dt;
    if (step >= left) {
        d->pos = goal;
        d->vel = 0;
        d->moving = 0;
        return;
    }
    d->pos += dir * step;
    d->vel = dir * speed;
}

/* The connection to the master is lost (a watched heartbeat or the SYNC
 * missing): EMCY 0x8130 and the error register's communication bit, and
 * where the power stage drives the motor (Operation Enabled, or Quick Stop
 * Active still ramping or holding) the abort connection option 0x6007
 * acts as the device control command it names. */
static void abort_connection(struct drive *d, const struct can_driver *can)
{
    d->error_register |= QRTCAN_ERRREG_COMM;
    if (d->state == QRTCAN_402_OPERATION_ENABLED ||
        d->state == QRTCAN_402_QUICK_STOP_ACTIVE) {
        switch (d->abort_option) {
        case 1:
            enter_fault(d, QRTCAN_EMCY_HEARTBEAT, QRTCAN_ERRREG_COMM, can);
            return; /* enter_fault sent the EMCY */
        case 2:
            d->state = QRTCAN_402_SWITCH_ON_DISABLED;
            d->vel = 0; /* power stage off: the motor stops where it is */
            d->moving = 0;
            break;
        case 3:
            d->state = QRTCAN_402_QUICK_STOP_ACTIVE;
            d->moving = 0;
            break;
        default: /* 0: no action */
            break;
        }
    }
    update_statusword(d);
    send_emcy(d, can, QRTCAN_EMCY_HEARTBEAT);
}

/* The vendor watchdog 0x2000: SYNC comes from the master alone, so its
 * absence while operational means the master (or the bus) is gone. Armed
 * by the first SYNC after NMT start. */
static void watchdog(struct drive *d, const struct can_driver *can, uint64_t t)
{
    if (d->watchdog_ms == 0 || d->nmt != QRTCAN_NMT_OPERATIONAL ||
        d->last_sync_us == 0 || d->watchdog_tripped ||
        t - d->last_sync_us <= (uint64_t)d->watchdog_ms * 1000u) {
        return;
    }
    d->watchdog_tripped = 1;
    abort_connection(d, can);
}

/* The heartbeat consumer 0x1016: an armed entry whose node has sent no
 * heartbeat for longer than the entry's time is a heartbeat event, once;
 * the entry waits for the node's next heartbeat to re-arm. */
static void heartbeat_consumer(struct drive *d, const struct can_driver *can,
                               uint64_t t)
{
    unsigned i;
    for (i = 0; i < DRIVE_HB_CONSUMERS; i++) {
        uint64_t limit_us = (uint64_t)(d->hb_consumer[i] & 0xFFFFu) * 1000u;
        if (d->hb_watch[i] == (uint8_t)DRIVE_HB_ARMED &&
            t - d->hb_seen_us[i] > limit_us) {
            d->hb_watch[i] = (uint8_t)DRIVE_HB_EXPIRED;
            abort_connection(d, can);
        }
    }
}

void drive_tick(struct drive *d, const struct can_driver *can)
{
    uint64_t t = now(can);
    double dt = (double)(t - d->last_tick_us) * 1e-6;
    struct qrtcan_frame f;
    if (dt > 0.05) {
        dt = 0.05; /* a stalled host must not teleport the motor */
    }
    d->last_tick_us = t;
    switch (d->state) {
    case QRTCAN_402_OPERATION_ENABLED:
        if (d->controlword & QRTCAN_CW_HALT) {
            brake(d, d->profile_decel, dt);
        } else if (d->moving) {
            profile_step(d, dt);
        }
        break;
    case QRTCAN_402_QUICK_STOP_ACTIVE:
        brake(d, d->quick_stop_decel, dt);
        break;
    case QRTCAN_402_FAULT_REACTION_ACTIVE:
        brake(d, d->quick_stop_decel, dt);
        if (d->vel == 0) {
            d->state = QRTCAN_402_FAULT; /* transition 14 */
        }
        break;
    default:
        d->vel = 0;
        break;
    }
    watchdog(d, can, t);
    heartbeat_consumer(d, can, t);
    update_statusword(d);
    if (d->heartbeat_ms != 0 && t >= d->next_heartbeat_us) {
        if (qrtcan_heartbeat_encode(d->cfg.node, (enum qrtcan_nmt_state)d->nmt,
                                    &f) == QRTCAN_OK) {
            send(d, can, &f);
        }
        d->next_heartbeat_us = t + (uint64_t)d->heartbeat_ms * 1000u;
    }
}
