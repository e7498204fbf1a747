/* libFuzzer target on the qrtcan frame decoders, the simulated drive's
 * frame handler and the CiA 402 master's: every input is a stream of
 * frames (id 2 bytes, dlc 1 byte, 8 data bytes), each handed to every
 * decoder, whose results must re-encode, and to a drive and to a master,
 * which must survive any sequence (the master's outbox never overflows
 * silently: it counts what it drops). The master also runs three drives in
 * a closed loop (its frames to them, theirs to it, the input's frames
 * injected into both), so that it gets past bring-up into moving and
 * stopping; after every stop it is asked for (the host watchdog's
 * included), no set-point may follow the quick stop, and while the host is
 * not alive no heartbeat of the master's may go out. */
#include <stddef.h>
#include <stdint.h>
#include <string.h>

#include "drive.h"
#include "qrtcan/master.h"
#include "qrtcan/qrtcan.h"

static uint64_t clock_us;

static int no_send(void *ctx, const struct qrtcan_frame *f)
{
    (void)ctx;
    (void)f;
    return 0;
}

static int no_receive(void *ctx, struct qrtcan_frame *f, uint32_t t)
{
    (void)ctx;
    (void)f;
    (void)t;
    return 0;
}

static uint64_t now(void *ctx)
{
    (void)ctx;
    return clock_us;
}

static const struct can_driver can = {0, no_send, no_receive, now};

/* the closed loop's bus: what the three drives sent since it was read */
#define BUS_MAX 256
static struct qrtcan_frame bus[BUS_MAX];
static int bus_count;

static int bus_send(void *ctx, const struct qrtcan_frame *f)
{
    (void)ctx;
    if (bus_count == BUS_MAX)
        return -1;
    bus[bus_count++] = *f;
    return 0;
}

static const struct can_driver loop_can = {0, bus_send, no_receive, now};

/* After a stop: every RPDO to the loop's drives carries quick stop. */
static void check_stop_is_last(const struct qrtcan_frame *out, int n)
{
    struct qrtcan_402_rpdo p;
    unsigned node;
    int k;
    for (k = 0; k < n; k++)
        if (out[k].id >= QRTCAN_FN_RPDO1 + 1u &&
            out[k].id <= QRTCAN_FN_RPDO1 + 3u &&
            (qrtcan_402_rpdo_decode(&out[k], &node, &p) != QRTCAN_OK ||
             p.controlword != QRTCAN_CW_CMD_QUICK_STOP))
            __builtin_trap();
}

static void decoders(const struct qrtcan_frame *f)
{
    struct qrtcan_frame g;
    enum qrtcan_kind kind;
    enum qrtcan_nmt_cmd cmd;
    enum qrtcan_nmt_state st;
    struct qrtcan_emcy e;
    struct qrtcan_sdo s;
    struct qrtcan_402_rpdo r;
    struct qrtcan_402_tpdo t;
    unsigned node, c;
    (void)qrtcan_classify(f, &kind, &node);
    if (qrtcan_nmt_decode(f, &cmd, &node) == QRTCAN_OK &&
        qrtcan_nmt_encode(cmd, node, &g) != QRTCAN_OK) {
        __builtin_trap();
    }
    if (qrtcan_sync_decode(f, &c) == QRTCAN_OK &&
        qrtcan_sync_encode(c, &g) != QRTCAN_OK) {
        __builtin_trap();
    }
    if (qrtcan_heartbeat_decode(f, &node, &st) == QRTCAN_OK &&
        qrtcan_heartbeat_encode(node, st, &g) != QRTCAN_OK) {
        __builtin_trap();
    }
    if (qrtcan_emcy_decode(f, &node, &e) == QRTCAN_OK &&
        (qrtcan_emcy_encode(node, &e, &g) != QRTCAN_OK ||
         memcmp(g.data, f->data, 8) != 0)) {
        __builtin_trap();
    }
    if (qrtcan_sdo_decode_request(f, &node, &s) == QRTCAN_OK) {
        (void)qrtcan_sdo_signed(&s);
        if (qrtcan_sdo_encode_request(node, &s, &g) != QRTCAN_OK) {
            __builtin_trap();
        }
    }
    if (qrtcan_sdo_decode_response(f, &node, &s) == QRTCAN_OK &&
        qrtcan_sdo_encode_response(node, &s, &g) != QRTCAN_OK) {
        __builtin_trap();
    }
    if (qrtcan_402_rpdo_decode(f, &node, &r) == QRTCAN_OK &&
        (qrtcan_402_rpdo_encode(node, &r, &g) != QRTCAN_OK ||
         memcmp(g.data, f->data, 6) != 0)) {
        __builtin_trap();
    }
    if (qrtcan_402_tpdo_decode(f, &node, &t) == QRTCAN_OK) {
        (void)qrtcan_402_state_from_statusword(t.statusword);
        if (qrtcan_402_tpdo_encode(node, &t, &g) != QRTCAN_OK) {
            __builtin_trap();
        }
    }
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    static struct drive d, loop[3];
    static struct qrtcan_master m;
    struct qrtcan_master_config mc;
    struct drive_config cfg;
    size_t i;
    int j;
    bus_count = 0;
    for (j = 0; j < 3; j++) {
        memset(&cfg, 0, sizeof cfg);
        cfg.node = (unsigned)j + 1;
        cfg.limit_min = -400000;
        cfg.limit_max = 400000;
        cfg.servo_error = 3;
        cfg.watchdog_ms = 200;
        drive_init(&loop[j], &cfg, &loop_can);
    }
    memset(&cfg, 0, sizeof cfg);
    cfg.node = 1;
    cfg.limit_min = -180000;
    cfg.limit_max = 180000;
    cfg.servo_error = 7;
    cfg.watchdog_ms = 50;
    cfg.heartbeat_ms = 10;
    clock_us = 1000000;
    drive_init(&d, &cfg, &can);
    qrtcan_master_config_default(&mc);
    if (qrtcan_master_init(&m, &mc, clock_us) != QRTCAN_OK)
        __builtin_trap();
    qrtcan_master_start(&m, clock_us);
    for (i = 0; i + 11 <= size; i += 11) {
        struct qrtcan_frame f, out[QRTCAN_MASTER_OUTBOX];
        struct qrtcan_master_status st;
        int stopped = 0, n, k;
        /* ids 0..0x7FF mostly, with the top bit of the first byte making
         * the occasional out-of-range identifier */
        f.id = (uint32_t)data[i] << 8 | data[i + 1];
        f.id = (data[i] & 0x80) ? f.id << 16 : f.id & 0x7FFu;
        f.dlc = data[i + 2];
        memcpy(f.data, &data[i + 3], 8);
        decoders(&f);
        drive_on_frame(&d, &f, &can);
        for (j = 0; j < 3; j++)
            drive_on_frame(&loop[j], &f, &loop_can);
        (void)qrtcan_master_on_frame(&m, &f, clock_us);
        clock_us += 1000u * (data[i + 2] >> 4);
        drive_tick(&d, &can);
        for (j = 0; j < 3; j++)
            drive_tick(&loop[j], &loop_can);
        qrtcan_master_tick(&m, clock_us);
        if (f.data[7] & 1) { /* sometimes a path, a stop or a bus error */
            static const double wp[2][3] = {{0, 0, 0}, {10, -5, 3}};
            int live =
                m.state != QRTCAN_MASTER_OFF && m.state != QRTCAN_MASTER_FAULT;
            if (f.data[6] & 1) {
                (void)qrtcan_master_set_path(&m, wp, 2, clock_us);
            } else if (f.data[6] & 2) {
                qrtcan_master_quick_stop(&m, clock_us);
                stopped = live;
            } else if (f.data[6] & 4) {
                qrtcan_master_bus_error(&m, clock_us);
                stopped = live;
            } else if (f.data[6] & 8) {
                int alive = !m.host_alive;
                qrtcan_master_set_host_alive(&m, alive, clock_us);
                stopped = live && !alive;
            }
        }
        n = qrtcan_master_take_frames(&m, out, QRTCAN_MASTER_OUTBOX);
        qrtcan_master_get_status(&m, &st);
        if (stopped)
            check_stop_is_last(out, n);
        for (k = 0; k < n && !st.host_alive; k++)
            if (out[k].id == QRTCAN_FN_HEARTBEAT + mc.master_node)
                __builtin_trap();
        for (k = 0; k < n; k++)
            for (j = 0; j < 3; j++)
                drive_on_frame(&loop[j], &out[k], &loop_can);
        for (k = 0; k < bus_count; k++) {
            (void)qrtcan_master_on_frame(&m, &bus[k], clock_us);
            for (j = 0; j < 3; j++)
                drive_on_frame(&loop[j], &bus[k], &loop_can);
        }
        bus_count = 0;
    }
    return 0;
}
