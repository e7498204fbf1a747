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

    if (failures) {
        fprintf(stderr, "test_servo_drive: %d checks failed\n", failures);
        return 1;
    }
    printf("test_servo_drive: all checks passed\n");
    return 0;
}
