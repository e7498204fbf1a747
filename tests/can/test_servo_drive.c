/* The simulated drive's firmware logic on an in-memory bus with a manual
 * clock: no SocketCAN needed, so this runs on every build (CI's kernel has
 * no CAN). The same scenarios as the VM test, checked frame by frame. */
#include <stdio.h>
#include <string.h>

#include "drive.h"
#include "qrtcan/qrtcan.h"

static int failures;

#define CHECK(cond)                                                            \
    do {                                                                       \
        if (!(cond)) {                                                         \
            fprintf(stderr, "%s:%d: CHECK(%s) failed\n", __FILE__, __LINE__,   \
                    #cond);                                                    \
            failures++;                                                        \
        }                                                                      \
    } while (0)

struct bus {
    uint64_t t;
    struct qrtcan_frame out[64];
    unsigned n_out;
};

static int bus_send(void *ctx, const struct qrtcan_frame *f)
{
    struct bus *b = ctx;
    if (b->n_out == 64) {
        return -1;
    }
    b->out[b->n_out++] = *f;
    return 0;
}

static int bus_receive(void *ctx, struct qrtcan_frame *f, uint32_t timeout_us)
{
    (void)ctx;
    (void)f;
    (void)timeout_us;
    return 0;
}

static uint64_t bus_now(void *ctx)
{
    return ((struct bus *)ctx)->t;
}

static struct bus bus;
static const struct can_driver can = {&bus, bus_send, bus_receive, bus_now};
static struct drive d;

static void run_ms(unsigned ms)
{
    unsigned i;
    for (i = 0; i < ms; i++) {
        bus.t += 1000;
        drive_tick(&d, &can);
    }
}

/* The last frame the drive sent with this COB-ID, or NULL. */
static const struct qrtcan_frame *last(uint32_t id)
{
    unsigned i;
    for (i = bus.n_out; i-- > 0;) {
        if (bus.out[i].id == id) {
            return &bus.out[i];
        }
    }
    return 0;
}

static struct qrtcan_sdo sdo(enum qrtcan_sdo_type type, uint16_t index,
                             uint8_t sub, uint8_t size, uint32_t data)
{
    struct qrtcan_frame f;
    struct qrtcan_sdo s = {type, index, sub, size, data}, r;
    unsigned node;
    bus.n_out = 0;
    qrtcan_sdo_encode_request(1, &s, &f);
    drive_on_frame(&d, &f, &can);
    memset(&r, 0, sizeof r);
    r.type = QRTCAN_SDO_ABORT;
    if (bus.n_out != 1 ||
        qrtcan_sdo_decode_response(&bus.out[0], &node, &r) != QRTCAN_OK) {
        r.data = 0xFFFFFFFFu; /* no answer */
    }
    return r;
}

static void rpdo(uint16_t cw, int32_t target)
{
    struct qrtcan_frame f;
    struct qrtcan_402_rpdo p = {cw, target};
    qrtcan_402_rpdo_encode(1, &p, &f);
    drive_on_frame(&d, &f, &can);
}

static struct qrtcan_402_tpdo sync_tpdo(void)
{
    struct qrtcan_frame f;
    struct qrtcan_402_tpdo t = {0, 0};
    unsigned node;
    const struct qrtcan_frame *p;
    bus.n_out = 0;
    qrtcan_sync_encode(0, &f);
    drive_on_frame(&d, &f, &can);
    p = last(0x181);
    CHECK(p != 0);
    if (p) {
        CHECK(qrtcan_402_tpdo_decode(p, &node, &t) == QRTCAN_OK);
    }
    return t;
}

static void nmt(enum qrtcan_nmt_cmd c)
{
    struct qrtcan_frame f;
    qrtcan_nmt_encode(c, 0, &f);
    drive_on_frame(&d, &f, &can);
}

static uint16_t last_emcy_code(void)
{
    const struct qrtcan_frame *p = last(0x081);
    struct qrtcan_emcy e;
    unsigned node;
    if (p == 0 || qrtcan_emcy_decode(p, &node, &e) != QRTCAN_OK) {
        return 0xFFFF;
    }
    return e.code;
}

static void enable(void)
{
    uint16_t cw = 0;
    int i;
    for (i = 0; i < 6; i++) {
        enum qrtcan_402_state st =
            qrtcan_402_state_from_statusword(sync_tpdo().statusword);
        if (st == QRTCAN_402_OPERATION_ENABLED) {
            break;
        }
        cw =
            qrtcan_402_controlword_toward(st, QRTCAN_402_OPERATION_ENABLED, cw);
        rpdo(cw, d.target);
    }
    CHECK(d.state == QRTCAN_402_OPERATION_ENABLED);
}

static void move_to(int32_t target, unsigned max_ms)
{
    unsigned ms;
    rpdo(0x0F, target);
    rpdo(0x1F, target); /* new setpoint */
    CHECK(sync_tpdo().statusword & QRTCAN_SW_SETPOINT_ACK);
    rpdo(0x0F, target);
    for (ms = 0; ms < max_ms && d.moving; ms += 10) {
        run_ms(10);
        sync_tpdo(); /* keeps the watchdog fed */
    }
}

/* A heartbeat of node, as if from another device on the bus. */
static void heartbeat_from(unsigned node)
{
    struct qrtcan_frame f;
    qrtcan_heartbeat_encode(node, QRTCAN_NMT_OPERATIONAL, &f);
    drive_on_frame(&d, &f, &can);
}

/* What the drive did while run_bus ran. */
struct seen {
    unsigned emcy_8130;       /* EMCY 0x8130 frames sent */
    uint64_t left_enabled_us; /* first tick out of Operation Enabled, 0 =
                                 never */
};

/* ms milliseconds of bus: the drive ticks every millisecond, a SYNC comes
 * every 10 ms (if sync) and a heartbeat every 50 ms from each of the n_hb
 * nodes in hb; what the drive sends is looked at, then dropped. */
static void run_bus(unsigned ms, int sync, const unsigned *hb, unsigned n_hb,
                    struct seen *s)
{
    unsigned i, k;
    for (i = 0; i < ms; i++) {
        struct qrtcan_frame f;
        bus.t += 1000;
        if (sync && bus.t / 1000 % 10 == 0) {
            qrtcan_sync_encode(0, &f);
            drive_on_frame(&d, &f, &can);
        }
        for (k = 0; k < n_hb && bus.t / 1000 % 50 == 0; k++) {
            heartbeat_from(hb[k]);
        }
        drive_tick(&d, &can);
        for (k = 0; k < bus.n_out; k++) {
            struct qrtcan_emcy e;
            unsigned node;
            if (bus.out[k].id == 0x081 &&
                qrtcan_emcy_decode(&bus.out[k], &node, &e) == QRTCAN_OK &&
                e.code == QRTCAN_EMCY_HEARTBEAT) {
                s->emcy_8130++;
            }
        }
        if (d.state != QRTCAN_402_OPERATION_ENABLED &&
            s->left_enabled_us == 0) {
            s->left_enabled_us = bus.t;
        }
        bus.n_out = 0;
    }
}

/* A drive just powered up (SYNC watchdog 0x2000 as given, 0 = off), NMT
 * started and enabled, at 0 counts. */
static void fresh(uint32_t watchdog_ms)
{
    struct drive_config cfg;
    memset(&cfg, 0, sizeof cfg);
    cfg.node = 1;
    cfg.limit_min = -400000;
    cfg.limit_max = 400000;
    cfg.watchdog_ms = watchdog_ms;
    cfg.heartbeat_ms = 100;
    bus.n_out = 0;
    drive_init(&d, &cfg, &can);
    nmt(QRTCAN_NMT_START);
    enable();
}

static void start_move(int32_t target)
{
    rpdo(0x0F, target);
    rpdo(0x1F, target); /* new setpoint */
    rpdo(0x0F, target);
    CHECK(d.moving);
}

/* CiA 301's heartbeat consumer (0x1016) and CiA 402's abort connection
 * option (0x6007); the SYNC watchdog (0x2000) fed by SYNC alone. */
static void heartbeat_consumer_tests(void)
{
    static const unsigned master[] = {127, 2, 3}, others[] = {2, 3};
    const uint32_t entry = (127u << 16) | 300u;
    struct qrtcan_sdo r;
    struct seen s;
    uint64_t t_last;
    unsigned i;
    int v;

    /* power-up: four entries, all unused: with no master heartbeat at all
     * the drive keeps moving and finishes its move, as a real drive with
     * no 0x1016 configured does */
    fresh(200);
    r = sdo(QRTCAN_SDO_READ, 0x1016, 0, 0, 0);
    CHECK(r.type == QRTCAN_SDO_READ_OK && r.size == 1 && r.data == 4);
    for (i = 1; i <= 4; i++) {
        r = sdo(QRTCAN_SDO_READ, 0x1016, (uint8_t)i, 0, 0);
        CHECK(r.type == QRTCAN_SDO_READ_OK && r.size == 4 && r.data == 0);
    }
    r = sdo(QRTCAN_SDO_WRITE, 0x1016, 0, 1, 2);
    CHECK(r.type == QRTCAN_SDO_ABORT && r.data == QRTCAN_SDO_ABORT_READ_ONLY);
    start_move(90000);
    memset(&s, 0, sizeof s);
    run_bus(3000, 1, others, 2, &s);
    CHECK(s.emcy_8130 == 0 && s.left_enabled_us == 0);
    CHECK(!d.moving && d.position_actual == 90000);

    /* entries: one per node; a second used entry for a node is refused
     * (CiA 301: general parameter incompatibility), an unused one (time 0)
     * or another node's is not; reserved bits 31..24 must be 0 */
    r = sdo(QRTCAN_SDO_WRITE, 0x1016, 1, 4, entry);
    CHECK(r.type == QRTCAN_SDO_WRITE_OK);
    r = sdo(QRTCAN_SDO_READ, 0x1016, 1, 0, 0);
    CHECK(r.type == QRTCAN_SDO_READ_OK && r.data == entry);
    r = sdo(QRTCAN_SDO_WRITE, 0x1016, 2, 4, (127u << 16) | 500u);
    CHECK(r.type == QRTCAN_SDO_ABORT &&
          r.data == QRTCAN_SDO_ABORT_INCOMPATIBLE);
    r = sdo(QRTCAN_SDO_READ, 0x1016, 2, 0, 0);
    CHECK(r.type == QRTCAN_SDO_READ_OK && r.data == 0);
    r = sdo(QRTCAN_SDO_WRITE, 0x1016, 2, 4, 127u << 16);
    CHECK(r.type == QRTCAN_SDO_WRITE_OK);
    r = sdo(QRTCAN_SDO_WRITE, 0x1016, 2, 4, (5u << 16) | 500u);
    CHECK(r.type == QRTCAN_SDO_WRITE_OK);
    r = sdo(QRTCAN_SDO_WRITE, 0x1016, 3, 4, (5u << 16) | 100u);
    CHECK(r.type == QRTCAN_SDO_ABORT &&
          r.data == QRTCAN_SDO_ABORT_INCOMPATIBLE);
    r = sdo(QRTCAN_SDO_WRITE, 0x1016, 3, 4, 0x01000000u | (9u << 16) | 100u);
    CHECK(r.type == QRTCAN_SDO_ABORT && r.data == QRTCAN_SDO_ABORT_VALUE);
    r = sdo(QRTCAN_SDO_WRITE, 0x1016, 1, 4, entry); /* its own node again */
    CHECK(r.type == QRTCAN_SDO_WRITE_OK);
    r = sdo(QRTCAN_SDO_WRITE, 0x1016, 2, 4, 0);
    CHECK(r.type == QRTCAN_SDO_WRITE_OK);

    /* not monitored before its node's first heartbeat; other drives'
     * heartbeats neither arm nor feed it */
    memset(&s, 0, sizeof s);
    run_bus(1000, 1, others, 2, &s);
    CHECK(s.emcy_8130 == 0 && s.left_enabled_us == 0);
    start_move(-300000);
    run_bus(500, 1, master, 3, &s);
    CHECK(s.emcy_8130 == 0 && d.moving);
    heartbeat_from(127);
    t_last = bus.t;
    run_bus(1000, 1, others, 2, &s);
    CHECK(d.state == QRTCAN_402_QUICK_STOP_ACTIVE);
    CHECK(s.left_enabled_us > t_last + 300000u &&
          s.left_enabled_us <= t_last + 301000u);
    CHECK(s.emcy_8130 == 1);
    CHECK(d.error_register & QRTCAN_ERRREG_COMM);
    CHECK(d.vel == 0.0 && d.position_actual > -300000);
    CHECK(d.hb_watch[0] == DRIVE_HB_EXPIRED);

    /* heartbeats resume: the entry re-arms (no second event while they
     * come), and fires again when they stop */
    memset(&s, 0, sizeof s);
    run_bus(600, 1, master, 3, &s);
    CHECK(s.emcy_8130 == 0 && d.hb_watch[0] == DRIVE_HB_ARMED);
    enable();
    start_move(0);
    run_bus(100, 1, master, 3, &s);
    heartbeat_from(127);
    t_last = bus.t;
    memset(&s, 0, sizeof s);
    run_bus(400, 1, others, 2, &s);
    CHECK(d.state == QRTCAN_402_QUICK_STOP_ACTIVE && s.emcy_8130 == 1);
    CHECK(s.left_enabled_us > t_last + 300000u &&
          s.left_enabled_us <= t_last + 301000u);

    /* reset communication restores the power-up 0x1016: no consumer */
    nmt(QRTCAN_NMT_RESET_COMM);
    r = sdo(QRTCAN_SDO_READ, 0x1016, 1, 0, 0);
    CHECK(r.type == QRTCAN_SDO_READ_OK && r.data == 0);

    /* 0x6007 takes 0..3 (0 is CiA 402's "no action") */
    r = sdo(QRTCAN_SDO_WRITE, 0x6007, 0, 2, 4);
    CHECK(r.type == QRTCAN_SDO_ABORT && r.data == QRTCAN_SDO_ABORT_VALUE);
    r = sdo(QRTCAN_SDO_WRITE, 0x6007, 0, 2, 0xFFFF); /* -1 */
    CHECK(r.type == QRTCAN_SDO_ABORT && r.data == QRTCAN_SDO_ABORT_VALUE);

    /* each abort connection option, from the consumer alone (no SYNC
     * watchdog) in the middle of a move */
    for (v = 0; v <= 3; v++) {
        fresh(0);
        r = sdo(QRTCAN_SDO_WRITE, 0x6007, 0, 2, (uint32_t)v);
        CHECK(r.type == QRTCAN_SDO_WRITE_OK);
        r = sdo(QRTCAN_SDO_READ, 0x6007, 0, 0, 0);
        CHECK(r.type == QRTCAN_SDO_READ_OK && r.data == (uint32_t)v);
        r = sdo(QRTCAN_SDO_WRITE, 0x1016, 1, 4, (127u << 16) | 100u);
        CHECK(r.type == QRTCAN_SDO_WRITE_OK);
        heartbeat_from(127);
        t_last = bus.t;
        start_move(300000);
        memset(&s, 0, sizeof s);
        run_bus(120, 1, others, 2, &s);
        CHECK(s.emcy_8130 == 1 && (d.error_register & QRTCAN_ERRREG_COMM));
        run_bus(300, 1, others, 2, &s);
        switch (v) {
        case 0: /* the event is signalled, the motion goes on */
            CHECK(d.state == QRTCAN_402_OPERATION_ENABLED && d.moving);
            CHECK(s.left_enabled_us == 0);
            break;
        case 1: /* Fault Reaction Active (quick stop ramp), then Fault */
            CHECK(d.state == QRTCAN_402_FAULT && d.vel == 0.0);
            CHECK(d.error_code == QRTCAN_EMCY_HEARTBEAT);
            break;
        case 2: /* power stage off: the motor stops where it is */
            CHECK(d.state == QRTCAN_402_SWITCH_ON_DISABLED && d.vel == 0.0);
            break;
        default: /* the quick stop ramp, then holding */
            CHECK(d.state == QRTCAN_402_QUICK_STOP_ACTIVE && d.vel == 0.0);
            break;
        }
        CHECK(v == 0 || (s.left_enabled_us > t_last + 100000u &&
                         s.left_enabled_us <= t_last + 101000u && !d.moving));
    }

    /* the SYNC watchdog: heartbeats, the master's included, do not feed
     * it; it trips its time after the last SYNC */
    fresh(200);
    start_move(300000);
    memset(&s, 0, sizeof s);
    run_bus(100, 1, master, 3, &s);
    t_last = bus.t / 10000 * 10000; /* the last SYNC */
    run_bus(400, 0, master, 3, &s);
    CHECK(d.state == QRTCAN_402_QUICK_STOP_ACTIVE && s.emcy_8130 == 1);
    CHECK(s.left_enabled_us > t_last + 200000u &&
          s.left_enabled_us <= t_last + 201000u);
}

int main(void)
{
    struct drive_config cfg;
    struct qrtcan_sdo r;
    struct qrtcan_402_tpdo t;
    enum qrtcan_nmt_state hb;
    unsigned node;
    double peak = 0;
    unsigned ms;

    memset(&cfg, 0, sizeof cfg);
    cfg.node = 1;
    cfg.limit_min = -180000;
    cfg.limit_max = 180000;
    cfg.servo_error = 25;
    cfg.watchdog_ms = 200;
    cfg.heartbeat_ms = 100;
    bus.t = 1000000;
    drive_init(&d, &cfg, &can);
    CHECK(bus.n_out == 1 && bus.out[0].id == 0x701 && bus.out[0].data[0] == 0);

    /* heartbeat producer: pre-operational, every 100 ms */
    bus.n_out = 0;
    run_ms(250);
    CHECK(bus.n_out == 2);
    CHECK(qrtcan_heartbeat_decode(&bus.out[0], &node, &hb) == QRTCAN_OK &&
          hb == QRTCAN_NMT_PRE_OP);

    /* SDO server */
    r = sdo(QRTCAN_SDO_READ, 0x1000, 0, 0, 0);
    CHECK(r.type == QRTCAN_SDO_READ_OK && r.data == 0x00020192u && r.size == 4);
    r = sdo(QRTCAN_SDO_READ, 0x1018, 4, 0, 0);
    CHECK(r.type == QRTCAN_SDO_READ_OK && r.data == 1);
    r = sdo(QRTCAN_SDO_READ, 0x6041, 0, 0, 0);
    CHECK(r.type == QRTCAN_SDO_READ_OK && r.size == 2 &&
          qrtcan_402_state_from_statusword((uint16_t)r.data) ==
              QRTCAN_402_SWITCH_ON_DISABLED);
    r = sdo(QRTCAN_SDO_WRITE, 0x6041, 0, 2, 0);
    CHECK(r.type == QRTCAN_SDO_ABORT && r.data == QRTCAN_SDO_ABORT_READ_ONLY);
    r = sdo(QRTCAN_SDO_READ, 0x1234, 0, 0, 0);
    CHECK(r.type == QRTCAN_SDO_ABORT && r.data == QRTCAN_SDO_ABORT_NO_OBJECT);
    r = sdo(QRTCAN_SDO_READ, 0x1018, 9, 0, 0);
    CHECK(r.type == QRTCAN_SDO_ABORT && r.data == QRTCAN_SDO_ABORT_NO_SUBINDEX);
    r = sdo(QRTCAN_SDO_WRITE, 0x6081, 0, 2, 5);
    CHECK(r.type == QRTCAN_SDO_ABORT && r.data == QRTCAN_SDO_ABORT_LENGTH);
    r = sdo(QRTCAN_SDO_WRITE, 0x6060, 0, 1, 3);
    CHECK(r.type == QRTCAN_SDO_ABORT && r.data == QRTCAN_SDO_ABORT_VALUE);
    r = sdo(QRTCAN_SDO_WRITE, 0x6060, 0, 1, 1);
    CHECK(r.type == QRTCAN_SDO_WRITE_OK);
    r = sdo(QRTCAN_SDO_WRITE, 0x6081, 0, 4, 60000);
    CHECK(r.type == QRTCAN_SDO_WRITE_OK && d.profile_velocity == 60000);

    /* no PDOs before NMT start */
    bus.n_out = 0;
    {
        struct qrtcan_frame f;
        qrtcan_sync_encode(0, &f);
        drive_on_frame(&d, &f, &can);
        CHECK(bus.n_out == 0);
    }
    nmt(QRTCAN_NMT_START);
    enable();

    /* a profile position move: trapezoid capped at the profile velocity,
     * settles at target + servo error */
    t = sync_tpdo();
    CHECK(t.position_actual == 0);
    rpdo(0x0F, 30000);
    rpdo(0x1F, 30000);
    rpdo(0x0F, 30000);
    for (ms = 0; ms < 5000 && d.moving; ms += 10) {
        double v;
        run_ms(10);
        sync_tpdo();
        v = d.vel < 0 ? -d.vel : d.vel;
        peak = v > peak ? v : peak;
    }
    t = sync_tpdo();
    CHECK(!d.moving);
    CHECK(t.position_actual == 30000 + 25);
    CHECK(t.statusword & QRTCAN_SW_TARGET_REACHED);
    CHECK(peak <= 60000.0 + 1e-6 && peak > 59000.0);
    /* 30000 counts at 60000/s with 180000/s^2 takes 0.5 + 1/3 s */
    CHECK(ms >= 780 && ms <= 900);

    /* beyond the limit: clamped, internal limit active */
    move_to(500000, 10000);
    t = sync_tpdo();
    CHECK(t.position_actual == 180000 + 25);
    CHECK(t.statusword & QRTCAN_SW_INTERNAL_LIMIT);
    move_to(0, 10000);
    CHECK(d.position_actual == 25);

    /* watchdog: no SYNC for longer than 200 ms -> quick stop + EMCY 0x8130 */
    rpdo(0x0F, 100000);
    rpdo(0x1F, 100000);
    bus.n_out = 0;
    run_ms(150);
    CHECK(d.moving && last(0x081) == 0);
    run_ms(100);
    CHECK(last_emcy_code() == QRTCAN_EMCY_HEARTBEAT);
    CHECK(d.state == QRTCAN_402_QUICK_STOP_ACTIVE);
    run_ms(300);
    t = sync_tpdo();
    CHECK(qrtcan_402_state_from_statusword(t.statusword) ==
          QRTCAN_402_QUICK_STOP_ACTIVE);
    CHECK(d.vel == 0 && (t.statusword & QRTCAN_SW_TARGET_REACHED));
    enable(); /* round by Switch On Disabled */

    /* injected fault: EMCY, Fault Reaction Active, Fault; reset clears it */
    bus.n_out = 0;
    drive_fault(&d, QRTCAN_EMCY_OVERCURRENT, &can);
    CHECK(last_emcy_code() == QRTCAN_EMCY_OVERCURRENT);
    run_ms(5);
    t = sync_tpdo();
    CHECK(qrtcan_402_state_from_statusword(t.statusword) == QRTCAN_402_FAULT);
    r = sdo(QRTCAN_SDO_READ, 0x603F, 0, 0, 0);
    CHECK(r.type == QRTCAN_SDO_READ_OK && r.data == QRTCAN_EMCY_OVERCURRENT);
    r = sdo(QRTCAN_SDO_READ, 0x1001, 0, 0, 0);
    CHECK(r.type == QRTCAN_SDO_READ_OK && (r.data & QRTCAN_ERRREG_GENERIC));
    bus.n_out = 0;
    rpdo(0x00, 0);
    rpdo(0x80, 0);
    CHECK(last_emcy_code() == QRTCAN_EMCY_NO_ERROR);
    CHECK(d.state == QRTCAN_402_SWITCH_ON_DISABLED && d.error_register == 0);
    enable();

    /* garbage never disturbs it */
    {
        struct qrtcan_frame g;
        unsigned i;
        uint32_t x = 12345;
        for (i = 0; i < 100000; i++) {
            unsigned k;
            x = x * 1103515245u + 12345u;
            g.id = 0x180u + (x >> 8) % 0x600u;
            if (g.id == 0x201 || g.id == 0x000) {
                continue; /* valid commands would legitimately act */
            }
            g.dlc = (uint8_t)((x >> 4) % 16);
            for (k = 0; k < 8; k++) {
                x = x * 1103515245u + 12345u;
                g.data[k] = (uint8_t)(x >> 24);
            }
            bus.n_out = 0;
            drive_on_frame(&d, &g, &can);
        }
        CHECK(d.state == QRTCAN_402_OPERATION_ENABLED);
    }

    /* a muted node sends nothing */
    d.muted = 1;
    bus.n_out = 0;
    run_ms(500);
    CHECK(bus.n_out == 0);

    heartbeat_consumer_tests();

    if (failures) {
        fprintf(stderr, "test_servo_drive: %d checks failed\n", failures);
        return 1;
    }
    printf("test_servo_drive: all checks passed\n");
    return 0;
}
