/* The CiA 402 master (src/canmaster) against three simulated drives
 * (firmware_sim/drive.c, the servo_sim firmware) on a bus in memory, with
 * a virtual clock: bring-up, paths followed as straight joint-space
 * segments, alpha across +-180 degrees, quick stop and restart, a drive
 * fault, a mute drive, a bus error, and garbage frames. The same master
 * runs over real SocketCAN in the VM tests (tests/can). */
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "../../firmware_sim/drive.h"
#include "../unit/check.h"
#include "mem_bus.h"
#include "qrtcan/emcy.h"
#include "qrtcan/master.h"
#include "qrtcan/sdo.h"

#define STEP_US 250u

static struct drive drives[3];
static struct qrtcan_master m;
static double worst_off_line; /* degrees from the planned segment */
static int torque_dropped;    /* a drive passed Switch On Disabled */
static double peak_speed[3];  /* degrees a second, as the drives moved */

/* What the master put on the bus, as step() delivers it */
#define MASTER_HB_ID (QRTCAN_FN_HEARTBEAT + 127u)
static unsigned long hb_frames, sync_frames;
static uint64_t last_hb_us; /* the master's last heartbeat reached the drives */
static double hb_deg[3];    /* the drives' joints at that moment */
/* the SDO requests and NMT commands, in order, while recording */
struct sent {
    int nmt; /* 1: an NMT command (s unused) */
    unsigned node;
    struct qrtcan_sdo s;
};
static struct sent sent_log[256];
static int n_sent, recording;
/* an answer rewritten on its way to the master: a drive that reads back
 * another value than it was told */
static struct {
    int on;
    unsigned node;
    uint16_t index;
    uint8_t subindex;
    uint32_t value;
} tamper;

static void observe(const struct qrtcan_frame *f)
{
    struct sent e;
    int j;
    if (f->id == MASTER_HB_ID) {
        hb_frames++;
        last_hb_us = clock_us;
        for (j = 0; j < 3; j++)
            hb_deg[j] = drives[j].pos / 1000.0;
    }
    if (f->id == QRTCAN_FN_SYNC_EMCY)
        sync_frames++;
    if (!recording || n_sent == 256)
        return;
    memset(&e, 0, sizeof e);
    if (f->id == QRTCAN_FN_NMT && f->dlc == 2) {
        e.nmt = 1;
        e.node = f->data[1];
        sent_log[n_sent++] = e;
    } else if (qrtcan_sdo_decode_request(f, &e.node, &e.s) == QRTCAN_OK) {
        sent_log[n_sent++] = e;
    }
}

static void tamper_answer(struct qrtcan_frame *f)
{
    struct qrtcan_sdo s;
    unsigned node;
    if (!tamper.on || qrtcan_sdo_decode_response(f, &node, &s) != QRTCAN_OK ||
        node != tamper.node || s.type != QRTCAN_SDO_READ_OK ||
        s.index != tamper.index || s.subindex != tamper.subindex)
        return;
    s.data = tamper.value;
    CHECK(qrtcan_sdo_encode_response(node, &s, f) == QRTCAN_OK, "tamper");
}

/* Where in sent_log node was sent this SDO request (from index from on),
 * -1 if nowhere. */
static int find_sdo(int from, unsigned node, enum qrtcan_sdo_type type,
                    uint16_t index, uint8_t subindex)
{
    int i;
    for (i = from < 0 ? 0 : from; i < n_sent; i++)
        if (!sent_log[i].nmt && sent_log[i].node == node &&
            sent_log[i].s.type == type && sent_log[i].s.index == index &&
            sent_log[i].s.subindex == subindex)
            return i;
    return -1;
}

static int find_nmt(unsigned node)
{
    int i;
    for (i = 0; i < n_sent; i++)
        if (sent_log[i].nmt && sent_log[i].node == node)
            return i;
    return -1;
}

static double drive_deg(int j)
{
    return drives[j].pos / 1000.0;
}

/* One step of the world: master and drives exchange what they sent. */
static void step(void)
{
    struct qrtcan_frame out[QRTCAN_MASTER_OUTBOX];
    int n, i, j;
    clock_us += STEP_US;
    qrtcan_master_tick(&m, clock_us);
    n = qrtcan_master_take_frames(&m, out, QRTCAN_MASTER_OUTBOX);
    for (i = 0; i < n; i++) {
        observe(&out[i]);
        for (j = 0; j < 3; j++)
            drive_on_frame(&drives[j], &out[i], &can);
    }
    for (j = 0; j < 3; j++) {
        drive_tick(&drives[j], &can);
        if (fabs(drives[j].vel) / 1000.0 > peak_speed[j])
            peak_speed[j] = fabs(drives[j].vel) / 1000.0;
    }
    for (i = 0; i < bus_count; i++) {
        tamper_answer(&bus[i]);
        qrtcan_master_on_frame(&m, &bus[i], clock_us);
        for (j = 0; j < 3; j++)
            drive_on_frame(&drives[j], &bus[i], &can);
    }
    bus_count = 0;
}

/* How many frames with this id the master's outbox holds. */
static int queued(uint32_t id)
{
    int i, n = 0;
    for (i = 0; i < m.out_count; i++)
        n += m.out[(m.out_head + i) % QRTCAN_MASTER_OUTBOX].id == id;
    return n;
}

/* One step of the drives alone, the master dead (no longer called): they
 * still hear each other's heartbeats. Returns how many were sent. */
static int step_drives_only(void)
{
    int i, j, heartbeats = 0;
    clock_us += STEP_US;
    for (j = 0; j < 3; j++)
        drive_tick(&drives[j], &can);
    for (i = 0; i < bus_count; i++) {
        heartbeats += (bus[i].id & 0x780u) == QRTCAN_FN_HEARTBEAT;
        for (j = 0; j < 3; j++)
            drive_on_frame(&drives[j], &bus[i], &can);
    }
    bus_count = 0;
    return heartbeats;
}

/* One SYNC period on the master's side only, so that the outbox holds the
 * SYNC and the drives' set-point RPDOs when the caller stops. */
static void queue_sync_rpdos(void)
{
    clock_us += m.cfg.sync_period_us;
    qrtcan_master_tick(&m, clock_us);
    CHECK(m.out_count >= 4, "only %d frames queued at a SYNC", m.out_count);
}

/* Deliver the outbox after a stop; after its quick stop, no drive may be sent
 * another controlword (an "enable operation" would undo the stop). Returns
 * how many queued drive commands the stop withdrew. */
static unsigned long deliver_after_stop(const char *what,
                                        unsigned long withdrawn_before)
{
    struct qrtcan_frame out[QRTCAN_MASTER_OUTBOX];
    int stopped[3] = {0, 0, 0};
    int n, i, j;
    n = qrtcan_master_take_frames(&m, out, QRTCAN_MASTER_OUTBOX);
    for (i = 0; i < n; i++) {
        struct qrtcan_402_rpdo p;
        unsigned node;
        for (j = 0; j < 3; j++) {
            if (out[i].id != QRTCAN_FN_RPDO1 + m.drive[j].node)
                continue;
            if (qrtcan_402_rpdo_decode(&out[i], &node, &p) != QRTCAN_OK) {
                CHECK(0, "%s: malformed RPDO to drive %d", what, j + 1);
                continue;
            }
            if (p.controlword == QRTCAN_CW_CMD_QUICK_STOP)
                stopped[j] = 1;
            else
                CHECK(!stopped[j],
                      "%s: controlword 0x%04x to drive %d after its quick "
                      "stop",
                      what, p.controlword, j + 1);
        }
        for (j = 0; j < 3; j++)
            drive_on_frame(&drives[j], &out[i], &can);
    }
    for (j = 0; j < 3; j++)
        CHECK(stopped[j], "%s: no quick stop to drive %d", what, j + 1);
    return m.frames_withdrawn - withdrawn_before;
}

static enum qrtcan_master_state state(void)
{
    struct qrtcan_master_status st;
    qrtcan_master_get_status(&m, &st);
    return st.state;
}

static int run_until(enum qrtcan_master_state want, double seconds)
{
    uint64_t end = clock_us + (uint64_t)(seconds * 1e6);
    while (clock_us < end) {
        step();
        if (state() == want)
            return 1;
    }
    return 0;
}

/* Distance (degrees) of the drives' joint point from the straight segment
 * a-b (alpha unwrapped, as the drive counts it). */
static double off_segment(const double a[3], const double b[3])
{
    double p[3], ab[3], ap[3], t = 0.0, len2 = 0.0, d2 = 0.0;
    int j;
    for (j = 0; j < 3; j++) {
        p[j] = drive_deg(j);
        ab[j] = b[j] - a[j];
        ap[j] = p[j] - a[j];
        len2 += ab[j] * ab[j];
        t += ap[j] * ab[j];
    }
    t = len2 > 0.0 ? t / len2 : 0.0;
    t = t < 0.0 ? 0.0 : t > 1.0 ? 1.0 : t;
    for (j = 0; j < 3; j++)
        d2 += (ap[j] - t * ab[j]) * (ap[j] - t * ab[j]);
    return sqrt(d2);
}

/* Execute a path; wp in degrees, alpha as the planner gives it. unwrapped
 * holds the same waypoints with alpha continuous (what the drive sees). */
static int follow(const double (*wp)[3], const double (*unwrapped)[3], int n,
                  double seconds)
{
    uint64_t end = clock_us + (uint64_t)(seconds * 1e6);
    int rc = qrtcan_master_set_path(&m, wp, n, clock_us);
    CHECK(rc == QRTCAN_OK, "set_path refused: %d", rc);
    if (rc != QRTCAN_OK)
        return 0;
    while (clock_us < end) {
        struct qrtcan_master_status st;
        int k;
        double best = 1e9;
        step();
        /* the arm must be on one of the segments at every moment */
        for (k = 0; k + 1 < n; k++) {
            double d = off_segment(unwrapped[k], unwrapped[k + 1]);
            best = d < best ? d : best;
        }
        if (n > 1 && best > worst_off_line)
            worst_off_line = best;
        for (k = 0; k < 3; k++)
            torque_dropped |=
                drives[k].state == QRTCAN_402_SWITCH_ON_DISABLED ||
                drives[k].state == QRTCAN_402_READY_TO_SWITCH_ON;
        qrtcan_master_get_status(&m, &st);
        if (st.state == QRTCAN_MASTER_READY && st.path_done)
            return 1;
        if (st.state == QRTCAN_MASTER_FAULT)
            return 0;
    }
    return 0;
}

/* Drives at 0 and the master brought up with cfg (the defaults, the arm of
 * docs/spec.md section Arm, where NULL). */
static void power_up(const struct qrtcan_master_config *given)
{
    struct qrtcan_master_config cfg;
    int j;
    memset(drives, 0, sizeof drives);
    bus_count = 0;
    for (j = 0; j < 3; j++) {
        struct drive_config dc;
        memset(&dc, 0, sizeof dc);
        dc.node = (unsigned)j + 1;
        dc.limit_min = -400000;
        dc.limit_max = 400000;
        dc.servo_error = 3; /* 0.003 degrees */
        dc.watchdog_ms = 200;
        dc.heartbeat_ms = 0;
        dc.start_position = 0;
        drive_init(&drives[j], &dc, &can);
    }
    if (given)
        cfg = *given;
    else
        qrtcan_master_config_default(&cfg);
    CHECK(qrtcan_master_init(&m, &cfg, clock_us) == QRTCAN_OK, "init");
    qrtcan_master_start(&m, clock_us);
}

/* Bring-up where a drive does not keep its safety settings: the master
 * fails naming the drive and the object, and enables no drive, retry
 * after retry. */
static void refused(const char *what, unsigned node, uint16_t index)
{
    struct qrtcan_master_status st;
    int i, j, enabled = 0;
    CHECK(run_until(QRTCAN_MASTER_FAULT, 2.0), "%s: no fault", what);
    qrtcan_master_get_status(&m, &st);
    CHECK(st.reason == QRTCAN_REASON_SDO_ABORT && st.reason_node == node &&
              st.reason_code == index,
          "%s: %s, node %u, code %04x", what,
          qrtcan_master_reason_name(st.reason), st.reason_node, st.reason_code);
    for (i = 0; i < 16000; i++) { /* 4 s: retries every second */
        step();
        for (j = 0; j < 3; j++)
            enabled |= drives[j].state == QRTCAN_402_OPERATION_ENABLED ||
                       drives[j].nmt == QRTCAN_NMT_OPERATIONAL;
        enabled |=
            state() == QRTCAN_MASTER_ENABLING || state() == QRTCAN_MASTER_READY;
    }
    qrtcan_master_get_status(&m, &st);
    CHECK(!enabled, "%s: a drive was started or enabled", what);
    CHECK(st.recoveries >= 3 && st.reason == QRTCAN_REASON_SDO_ABORT &&
              st.reason_node == node && st.reason_code == index,
          "%s: after %lu retries %s node %u code %04x", what, st.recoveries,
          qrtcan_master_reason_name(st.reason), st.reason_node, st.reason_code);
}

int main(void)
{
    static const double path1[3][3] = {{0, 0, 0}, {20, 10, -15}, {-10, 35, 5}};
    static const double path2[2][3] = {{-10, 35, 5}, {170, 35, 5}};
    static const double wrap[2][3] = {{170, 35, 5}, {-170, 30, 0}};
    static const double wrap_unwrapped[2][3] = {{170, 35, 5}, {190, 30, 0}};
    struct qrtcan_master_status st;
    struct qrtcan_master_config bad;
    double here[1][3];
    int j, i;

    /* configuration refused */
    qrtcan_master_config_default(&bad);
    bad.node[1] = bad.node[0];
    CHECK(qrtcan_master_init(&m, &bad, 0) == QRTCAN_E_ARG, "repeated node");
    qrtcan_master_config_default(&bad);
    bad.scale[2].counts_per_deg = NAN;
    CHECK(qrtcan_master_init(&m, &bad, 0) == QRTCAN_E_ARG, "NaN scale");
    qrtcan_master_config_default(&bad);
    bad.limit_deg[1][0] = bad.limit_deg[1][1];
    CHECK(qrtcan_master_init(&m, &bad, 0) == QRTCAN_E_ARG, "empty limits");
    qrtcan_master_config_default(&bad);
    bad.limit_deg[2][1] = NAN;
    CHECK(qrtcan_master_init(&m, &bad, 0) == QRTCAN_E_ARG, "NaN limit");
    qrtcan_master_config_default(&bad);
    bad.limit_deg[0][1] = 200.0;
    CHECK(qrtcan_master_init(&m, &bad, 0) == QRTCAN_E_ARG, "limit past 180");

    /* limits, checked before anything else about the path: alpha on
     * [-170, 170] does not wrap, so a step of more than 180 degrees (which
     * the drives would take the short way, through its dead zone) is
     * refused even between two waypoints inside */
    {
        static struct qrtcan_master fenced;
        static const double ok_path[3][3] = {
            {0, 0, 0}, {170, -40, 140}, {-9, 180, -180}};
        static const double past[4][2][3] = {{{0, 0, 0}, {170.01, 0, 0}},
                                             {{0, 0, 0}, {0, -40.01, 0}},
                                             {{0, 0, 0}, {0, 0, 140.01}},
                                             {{0, 0, 0}, {0, 180.01, 0}}};
        static const double long_way[3][3] = {
            {0, 0, 0}, {160, 0, 0}, {-160, 0, 0}};
        struct qrtcan_master_config fence;
        qrtcan_master_config_default(&fence);
        fence.limit_deg[0][0] = -170.0;
        fence.limit_deg[0][1] = 170.0;
        CHECK(qrtcan_master_init(&fenced, &fence, 0) == QRTCAN_OK, "fence");
        /* inside: refused only because the drives are not up (E_CMD) */
        CHECK(qrtcan_master_set_path(&fenced, ok_path, 3, 0) == QRTCAN_E_CMD,
              "a path on the limits was refused as outside them");
        for (i = 0; i < 4; i++)
            CHECK(qrtcan_master_set_path(&fenced, past[i], 2, 0) ==
                      QRTCAN_E_RANGE,
                  "waypoint past a limit accepted (case %d)", i);
        CHECK(qrtcan_master_set_path(&fenced, long_way, 3, 0) == QRTCAN_E_RANGE,
              "alpha 160 -> -160 would go the short way through 180");
    }

    /* configuration refused: the drives' wait for our heartbeat must be
     * longer than our heartbeat period */
    qrtcan_master_config_default(&bad);
    CHECK(bad.consumer_heartbeat_ms == 300, "default consumer time %u",
          bad.consumer_heartbeat_ms);
    bad.consumer_heartbeat_ms = 0;
    CHECK(qrtcan_master_init(&m, &bad, 0) == QRTCAN_E_ARG, "consumer 0 ms");
    bad.consumer_heartbeat_ms = 100;
    CHECK(qrtcan_master_init(&m, &bad, 0) == QRTCAN_E_ARG,
          "consumer time equal to the heartbeat period");
    bad.consumer_heartbeat_ms = 101;
    CHECK(qrtcan_master_init(&m, &bad, 0) == QRTCAN_OK, "consumer 101 ms");

    /* bring-up: before NMT start, each drive is told to watch our
     * heartbeat (0x1016:1 = node 127, 300 ms) and to quick-stop when it
     * stops (0x6007 = 3), and both are read back */
    n_sent = 0;
    recording = 1;
    power_up(NULL);
    CHECK(run_until(QRTCAN_MASTER_READY, 2.0), "drives not enabled");
    recording = 0;
    for (j = 0; j < 3; j++) {
        unsigned node = (unsigned)j + 1;
        int w1 = find_sdo(0, node, QRTCAN_SDO_WRITE, 0x1016, 1);
        int r1 = find_sdo(w1, node, QRTCAN_SDO_READ, 0x1016, 1);
        int w2 = find_sdo(0, node, QRTCAN_SDO_WRITE, 0x6007, 0);
        int r2 = find_sdo(w2, node, QRTCAN_SDO_READ, 0x6007, 0);
        int start = find_nmt(node);
        CHECK(w1 >= 0 && sent_log[w1].s.size == 4 &&
                  sent_log[w1].s.data == ((127u << 16) | 300u),
              "drive %u: 0x1016:1 write %d (0x%08x)", node, w1,
              w1 >= 0 ? (unsigned)sent_log[w1].s.data : 0u);
        CHECK(w2 >= 0 && sent_log[w2].s.size == 2 && sent_log[w2].s.data == 3,
              "drive %u: 0x6007 write %d", node, w2);
        CHECK(r1 > w1 && r2 > w2, "drive %u: read-backs %d %d", node, r1, r2);
        CHECK(start > r1 && start > r2,
              "drive %u started (%d) before its "
              "read-backs (%d, %d)",
              node, start, r1, r2);
        CHECK(drives[j].hb_consumer[0] == ((127u << 16) | 300u) &&
                  drives[j].abort_option == 3,
              "drive %u holds 0x%08x, %d", node,
              (unsigned)drives[j].hb_consumer[0], drives[j].abort_option);
        CHECK(drives[j].hb_watch[0] == DRIVE_HB_ARMED,
              "drive %u does not watch our heartbeat", node);
        CHECK(drives[j].state == QRTCAN_402_OPERATION_ENABLED, "drive %d in %s",
              j + 1, qrtcan_402_state_name(drives[j].state));
        CHECK(drives[j].mode_display == QRTCAN_MODE_PROFILE_POSITION,
              "drive %d mode %d", j + 1, drives[j].mode_display);
        CHECK(drives[j].nmt == QRTCAN_NMT_OPERATIONAL, "drive %d NMT", j + 1);
    }
    qrtcan_master_get_status(&m, &st);
    CHECK(st.host_alive && st.heartbeat_produced, "host %d heartbeat %d",
          st.host_alive, st.heartbeat_produced);

    /* a path: every moment on a segment, every waypoint reached */
    CHECK(follow(path1, path1, 3, 20.0), "path 1 not completed");
    for (j = 0; j < 3; j++)
        CHECK(fabs(drive_deg(j) - path1[2][j]) < 0.01, "joint %d at %g", j,
              drive_deg(j));
    CHECK(worst_off_line < 0.05, "left the segments by %g deg", worst_off_line);
    printf("path 1: worst distance from the planned segments %.4f deg\n",
           worst_off_line);

    /* a joint that does not move must not hold the segment up: the drives
     * settle at target + servo error, and a crawling profile would take
     * seconds over those last counts */
    {
        static const double still_eta[2][3] = {{-10, 35, 5}, {10, 45, 5}};
        uint64_t t0;
        /* eta exactly on its target (as after power-up): its step is 0 */
        drives[2].pos = 5000.0;
        for (i = 0; i < 40; i++)
            step();
        t0 = clock_us;
        CHECK(follow(still_eta, still_eta, 2, 20.0), "segment with eta still");
        CHECK(clock_us - t0 < 2500000, "a 20 degree segment took %.2f s",
              (double)(clock_us - t0) * 1e-6);
        static const double back[2][3] = {{10, 45, 5}, {-10, 35, 5}};
        CHECK(follow(back, back, 2, 20.0), "and back");
    }

    /* alpha across +-180 the short way: the drive goes 170 -> 190 */
    CHECK(follow(path2, path2, 2, 20.0), "path 2 not completed");
    worst_off_line = 0.0;
    CHECK(follow(wrap, wrap_unwrapped, 2, 20.0), "wrap path not completed");
    CHECK(fabs(drive_deg(0) - 190.0) < 0.01, "alpha drive at %g, not 190",
          drive_deg(0));
    CHECK(worst_off_line < 0.05, "wrap left the segment by %g deg",
          worst_off_line);
    qrtcan_master_get_status(&m, &st);
    CHECK(fabs(st.joints_deg[0] + 170.0) < 0.01, "alpha reported %g",
          st.joints_deg[0]);

    /* refused: a path that does not start where the arm is */
    {
        static const double far[2][3] = {{0, 0, 0}, {10, 10, 10}};
        CHECK(qrtcan_master_set_path(&m, far, 2, clock_us) == QRTCAN_E_RANGE,
              "a path from elsewhere must be refused");
        static const double nan_path[2][3] = {{-170, 30, 0}, {NAN, 0, 0}};
        static const double sigma_past[2][3] = {{-170, 30, 0}, {-170, 181, 0}};
        CHECK(qrtcan_master_set_path(&m, nan_path, 2, clock_us) == QRTCAN_E_ARG,
              "NaN waypoint");
        /* alpha wraps with the default limits; sigma does not */
        CHECK(qrtcan_master_set_path(&m, sigma_past, 2, clock_us) ==
                  QRTCAN_E_RANGE,
              "sigma 181 accepted");
    }

    /* quick stop in the middle of a move, then a new path from there */
    {
        static const double long_move[2][3] = {{-170, 30, 0}, {-60, 90, 60}};
        uint64_t t0;
        double before[3];
        CHECK(qrtcan_master_set_path(&m, long_move, 2, clock_us) == QRTCAN_OK,
              "long move");
        for (i = 0; i < 4000; i++)
            step(); /* 1 s in */
        CHECK(state() == QRTCAN_MASTER_MOVING, "not moving: %s",
              qrtcan_master_state_name(state()));
        {
            unsigned long before_stop = m.frames_withdrawn;
            queue_sync_rpdos();
            qrtcan_master_quick_stop(&m, clock_us);
            CHECK(deliver_after_stop("quick stop", before_stop) >= 3,
                  "the queued set-points were not withdrawn");
        }
        CHECK(qrtcan_master_set_path(&m, long_move, 2, clock_us) ==
                  QRTCAN_E_CMD,
              "a path while the stop ramps down must be refused");
        t0 = clock_us;
        for (i = 0; i < 8000; i++)
            step();
        for (j = 0; j < 3; j++) {
            CHECK(drives[j].state == QRTCAN_402_QUICK_STOP_ACTIVE,
                  "drive %d in %s after quick stop", j + 1,
                  qrtcan_402_state_name(drives[j].state));
            CHECK(drives[j].vel == 0.0, "drive %d still moving", j + 1);
            before[j] = drive_deg(j);
        }
        (void)t0;
        qrtcan_master_get_status(&m, &st);
        CHECK(st.state == QRTCAN_MASTER_STOPPED &&
                  st.reason == QRTCAN_REASON_COMMANDED,
              "state %s reason %s", qrtcan_master_state_name(st.state),
              qrtcan_master_reason_name(st.reason));
        for (i = 0; i < 4000; i++)
            step();
        for (j = 0; j < 3; j++)
            CHECK(fabs(drive_deg(j) - before[j]) < 1e-9, "drifted after stop");
        for (j = 0; j < 3; j++)
            here[0][j] = st.joints_deg[j];
        {
            double resume[2][3], resume_unwrapped[2][3];
            for (j = 0; j < 3; j++) {
                resume[0][j] = here[0][j];
                resume[1][j] = long_move[1][j];
                resume_unwrapped[0][j] = drive_deg(j);
                resume_unwrapped[1][j] = long_move[1][j];
            }
            resume_unwrapped[1][0] =
                drive_deg(0) + (long_move[1][0] - here[0][0]);
            worst_off_line = 0.0;
            torque_dropped = 0;
            CHECK(follow((const double(*)[3])resume,
                         (const double(*)[3])resume_unwrapped, 2, 20.0),
                  "no restart after a quick stop");
            CHECK(!torque_dropped, "the restart switched a drive off");
            CHECK(worst_off_line < 0.05, "restart left the segment by %g",
                  worst_off_line);
        }
    }

    /* a drive fault while moving: everyone stops, the master says who and
     * why, recovers, and the next path runs */
    {
        static const double move[2][3] = {{-60, 90, 60}, {0, 40, 0}};
        CHECK(qrtcan_master_set_path(&m, move, 2, clock_us) == QRTCAN_OK,
              "move");
        for (i = 0; i < 2000; i++)
            step();
        drive_fault(&drives[1], 0x2310, &can);
        for (i = 0; i < 40; i++)
            step();
        qrtcan_master_get_status(&m, &st);
        CHECK(st.state == QRTCAN_MASTER_FAULT &&
                  st.reason == QRTCAN_REASON_DRIVE_FAULT &&
                  st.reason_node == 2 && st.reason_code == 0x2310,
              "fault: %s %s node %u code %04x",
              qrtcan_master_state_name(st.state),
              qrtcan_master_reason_name(st.reason), st.reason_node,
              st.reason_code);
        CHECK(drives[0].state == QRTCAN_402_QUICK_STOP_ACTIVE &&
                  drives[2].state == QRTCAN_402_QUICK_STOP_ACTIVE,
              "the healthy drives were not stopped: %s %s",
              qrtcan_402_state_name(drives[0].state),
              qrtcan_402_state_name(drives[2].state));
        CHECK(run_until(QRTCAN_MASTER_READY, 5.0), "no recovery from fault");
        qrtcan_master_get_status(&m, &st);
        CHECK(st.recoveries >= 1, "recoveries %lu", st.recoveries);
        {
            double from[2][3];
            for (j = 0; j < 3; j++) {
                from[0][j] = st.joints_deg[j];
                from[1][j] = move[1][j];
            }
            CHECK(qrtcan_master_set_path(&m, (const double(*)[3])from, 2,
                                         clock_us) == QRTCAN_OK,
                  "path after recovery");
            CHECK(run_until(QRTCAN_MASTER_READY, 20.0), "path after fault");
            CHECK(fabs(drive_deg(1) - 0.0) < 40.01, "sigma");
        }
    }

    /* a drive that stops answering: heartbeat lost, then back */
    {
        for (j = 0; j < 3; j++)
            drives[j].heartbeat_ms = 50; /* the master asked for these */
        for (i = 0; i < 2000; i++)
            step();
        drives[2].muted = 1;
        CHECK(run_until(QRTCAN_MASTER_FAULT, 1.0), "mute drive unnoticed");
        qrtcan_master_get_status(&m, &st);
        CHECK(st.reason == QRTCAN_REASON_HEARTBEAT_LOST && st.reason_node == 3,
              "reason %s node %u", qrtcan_master_reason_name(st.reason),
              st.reason_node);
        for (i = 0; i < 12000; i++)
            step(); /* retries time out on SDO while it stays mute */
        qrtcan_master_get_status(&m, &st);
        CHECK(st.state == QRTCAN_MASTER_FAULT, "mute drive: %s",
              qrtcan_master_state_name(st.state));
        drives[2].muted = 0;
        CHECK(run_until(QRTCAN_MASTER_READY, 5.0),
              "no recovery when the drive answers again");
    }

    /* the caller's bus fails: fault, then recovery */
    qrtcan_master_bus_error(&m, clock_us);
    qrtcan_master_get_status(&m, &st);
    CHECK(st.state == QRTCAN_MASTER_FAULT && st.reason == QRTCAN_REASON_BUS,
          "bus error: %s", qrtcan_master_state_name(st.state));
    CHECK(run_until(QRTCAN_MASTER_READY, 5.0), "no recovery from bus error");

    /* garbage: never acted on, counted, nothing moves */
    {
        uint64_t seed = 12345;
        unsigned long before_bad;
        double pos[3];
        qrtcan_master_get_status(&m, &st);
        before_bad = st.frames_malformed + st.frames_ignored;
        for (j = 0; j < 3; j++)
            pos[j] = drive_deg(j);
        for (i = 0; i < 20000; i++) {
            struct qrtcan_frame f;
            int b;
            seed = seed * 6364136223846793005ULL + 1442695040888963407ULL;
            f.id = (uint32_t)(seed >> 33) & 0xFFF;
            f.dlc = (uint8_t)((seed >> 20) % 10);
            for (b = 0; b < 8; b++)
                f.data[b] = (uint8_t)(seed >> (b * 7));
            /* identifiers our drives use get a length no such frame has:
             * malformed, so it must be counted and never acted upon */
            if ((f.id & 0x780) == 0x180 || (f.id & 0x780) == 0x700 ||
                (f.id & 0x780) == 0x080 || (f.id & 0x780) == 0x580)
                f.dlc = 0;
            qrtcan_master_on_frame(&m, &f, clock_us);
        }
        for (i = 0; i < 400; i++)
            step();
        qrtcan_master_get_status(&m, &st);
        CHECK(st.state == QRTCAN_MASTER_READY, "garbage changed state to %s",
              qrtcan_master_state_name(st.state));
        CHECK(st.frames_malformed + st.frames_ignored - before_bad >= 20000,
              "garbage not counted");
        for (j = 0; j < 3; j++)
            CHECK(fabs(drive_deg(j) - pos[j]) < 0.01, "garbage moved joint %d",
                  j);
    }

    /* shutdown in the middle of a move: quick stop, and the drives hold
     * (their watchdogs see the master go quiet) instead of switching off */
    {
        double from[2][3];
        qrtcan_master_get_status(&m, &st);
        for (j = 0; j < 3; j++) {
            from[0][j] = st.joints_deg[j];
            from[1][j] = st.joints_deg[j] + 30.0;
        }
        CHECK(qrtcan_master_set_path(&m, (const double(*)[3])from, 2,
                                     clock_us) == QRTCAN_OK,
              "move before shutdown");
        for (i = 0; i < 2000; i++)
            step();
        {
            unsigned long before_stop = m.frames_withdrawn;
            queue_sync_rpdos();
            qrtcan_master_shutdown(&m, clock_us);
            CHECK(deliver_after_stop("shutdown", before_stop) >= 3,
                  "the queued set-points were not withdrawn");
        }
        for (i = 0; i < 8000; i++)
            step();
        for (j = 0; j < 3; j++) {
            CHECK(drives[j].state == QRTCAN_402_QUICK_STOP_ACTIVE ||
                      drives[j].state == QRTCAN_402_FAULT,
                  "drive %d in %s after shutdown", j + 1,
                  qrtcan_402_state_name(drives[j].state));
            CHECK(drives[j].vel == 0.0, "drive %d moves after shutdown", j + 1);
            CHECK(fabs(drive_deg(j) - from[1][j]) > 1.0,
                  "drive %d finished the move despite the shutdown", j + 1);
        }
    }

    /* joints rated differently (qrtpland's and qrtplan-exec's --speed and
     * --accel X,Y,Z): every drive within its own speed, still on the
     * segments, the slowest joint at its own rating setting the pace */
    {
        /* sigma, the slowest for path1's steps, must run at its rating */
        static const double rated_speed[3] = {40, 10, 20};
        static const double rated_accel[3] = {80, 20, 40};
        struct qrtcan_master_config rated;
        qrtcan_master_config_default(&rated);
        for (j = 0; j < 3; j++) {
            rated.max_speed_deg_s[j] = rated_speed[j];
            rated.max_accel_deg_s2[j] = rated_accel[j];
        }
        power_up(&rated);
        CHECK(run_until(QRTCAN_MASTER_READY, 2.0), "rated drives not enabled");
        worst_off_line = 0.0;
        for (j = 0; j < 3; j++)
            peak_speed[j] = 0.0;
        CHECK(follow(path1, path1, 3, 40.0), "rated path not completed");
        CHECK(worst_off_line < 0.05, "rated drives left the segments by %g deg",
              worst_off_line);
        for (j = 0; j < 3; j++)
            CHECK(peak_speed[j] >= 0.95 * rated_speed[j] * (j == 1) &&
                      peak_speed[j] <= rated_speed[j] * 1.01,
                  "joint %d peaked at %g deg/s, rated %g", j, peak_speed[j],
                  rated_speed[j]);
        printf("rated joints: peaks %.2f %.2f %.2f deg/s, worst distance "
               "from the segments %.4f deg\n",
               peak_speed[0], peak_speed[1], peak_speed[2], worst_off_line);
    }
    /* a drive that refuses its heartbeat consumer (it already watches node
     * 127 in another entry: CiA 301's "general parameter
     * incompatibility"), or reads back another value than it was told,
     * is never enabled */
    power_up(NULL);
    drives[1].hb_consumer[1] = (127u << 16) | 500u;
    refused("0x1016 refused by drive 2", 2, 0x1016);
    power_up(NULL);
    tamper.on = 1;
    tamper.node = 3;
    tamper.index = 0x6007;
    tamper.subindex = 0;
    tamper.value = 1; /* fault instead of quick stop */
    refused("0x6007 read back as 1 by drive 3", 3, 0x6007);
    power_up(NULL);
    tamper.node = 1;
    tamper.index = 0x1016;
    tamper.subindex = 1;
    tamper.value = (127u << 16) | 3000u;
    refused("0x1016:1 read back as 3000 ms by drive 1", 1, 0x1016);
    tamper.on = 0;

    /* the host watchdog: with alive = 0 mid-move the master queues quick
     * stops, produces no heartbeat (so the drives' consumers expire too),
     * keeps the SYNC and the positions, refuses paths and takes the drives'
     * heartbeat events for the stop they are; with alive = 1 the heartbeat
     * comes back at once and the arm stays stopped until the next path */
    {
        static const double far_move[2][3] = {{0, 0, 0}, {90, 60, -60}};
        double from[2][3];
        unsigned long hb0, sync0, recoveries;
        power_up(NULL);
        CHECK(run_until(QRTCAN_MASTER_READY, 2.0), "host watchdog: bring-up");
        CHECK(qrtcan_master_set_path(&m, far_move, 2, clock_us) == QRTCAN_OK,
              "host watchdog: path");
        for (i = 0; i < 4000; i++)
            step();
        CHECK(state() == QRTCAN_MASTER_MOVING, "host watchdog: %s",
              qrtcan_master_state_name(state()));
        {
            /* the tick due for a heartbeat: it, a SYNC and the set-points
             * queued when the host watchdog trips; the heartbeat is
             * withdrawn with the set-points */
            unsigned long before_stop = m.frames_withdrawn;
            clock_us = m.last_heartbeat_us + m.cfg.master_heartbeat_us;
            qrtcan_master_tick(&m, clock_us);
            CHECK(queued(MASTER_HB_ID) == 1 && m.out_count >= 5,
                  "%d heartbeats in %d frames queued", queued(MASTER_HB_ID),
                  m.out_count);
            qrtcan_master_set_host_alive(&m, 0, clock_us);
            CHECK(queued(MASTER_HB_ID) == 0,
                  "a heartbeat queued before the host watchdog tripped is "
                  "still queued");
            CHECK(deliver_after_stop("host watchdog", before_stop) >= 3,
                  "the queued set-points were not withdrawn");
        }
        qrtcan_master_get_status(&m, &st);
        CHECK(st.state == QRTCAN_MASTER_STOPPED &&
                  st.reason == QRTCAN_REASON_HOST_WATCHDOG && !st.host_alive &&
                  !st.heartbeat_produced,
              "host not alive: %s, %s, alive %d, heartbeat %d",
              qrtcan_master_state_name(st.state),
              qrtcan_master_reason_name(st.reason), st.host_alive,
              st.heartbeat_produced);
        hb0 = hb_frames;
        sync0 = sync_frames;
        for (i = 0; i < 8000; i++)
            step(); /* 2 s: 20 heartbeat periods */
        CHECK(hb_frames == hb0, "%lu heartbeats while the host is not alive",
              hb_frames - hb0);
        CHECK(sync_frames - sync0 >= 190, "only %lu SYNC in 2 s",
              sync_frames - sync0);
        qrtcan_master_get_status(&m, &st);
        for (j = 0; j < 3; j++) {
            CHECK(drives[j].state == QRTCAN_402_QUICK_STOP_ACTIVE &&
                      drives[j].vel == 0.0,
                  "drive %d in %s", j + 1,
                  qrtcan_402_state_name(drives[j].state));
            CHECK(drives[j].hb_watch[0] == DRIVE_HB_EXPIRED &&
                      m.drive[j].last_emcy == QRTCAN_EMCY_HEARTBEAT,
                  "drive %d: its heartbeat consumer did not expire", j + 1);
            CHECK(fabs(st.joints_deg[j] - drive_deg(j)) < 0.01,
                  "joint %d reported %g, at %g", j, st.joints_deg[j],
                  drive_deg(j));
            from[0][j] = st.joints_deg[j];
            from[1][j] = 0.0;
        }
        CHECK(st.state == QRTCAN_MASTER_STOPPED &&
                  st.reason == QRTCAN_REASON_HOST_WATCHDOG,
              "after the drives' heartbeat events: %s, %s",
              qrtcan_master_state_name(st.state),
              qrtcan_master_reason_name(st.reason));
        CHECK(qrtcan_master_set_path(&m, (const double(*)[3])from, 2,
                                     clock_us) == QRTCAN_E_CMD,
              "a path while the host is not alive");
        qrtcan_master_set_host_alive(&m, 0, clock_us);
        CHECK(m.out_count == 0, "a repeated alive = 0 queued %d frames",
              m.out_count);

        hb0 = hb_frames;
        qrtcan_master_set_host_alive(&m, 1, clock_us);
        step();
        CHECK(hb_frames == hb0 + 1, "heartbeat not resumed at once");
        for (i = 0; i < 4000; i++)
            step();
        CHECK(hb_frames - hb0 == 11, "%lu heartbeats in the second after",
              hb_frames - hb0);
        qrtcan_master_get_status(&m, &st);
        CHECK(st.state == QRTCAN_MASTER_STOPPED && st.host_alive &&
                  st.heartbeat_produced,
              "host alive again: %s, alive %d, heartbeat %d",
              qrtcan_master_state_name(st.state), st.host_alive,
              st.heartbeat_produced);
        for (j = 0; j < 3; j++) {
            CHECK(drives[j].state == QRTCAN_402_QUICK_STOP_ACTIVE &&
                      drives[j].vel == 0.0,
                  "drive %d moved before a path", j + 1);
            CHECK(drives[j].hb_watch[0] == DRIVE_HB_ARMED,
                  "drive %d: consumer not re-armed", j + 1);
        }
        CHECK(
            follow((const double(*)[3])from, (const double(*)[3])from, 2, 20.0),
            "no path after the host came back");

        /* a fault while the host is not alive: no bring-up until it is */
        qrtcan_master_set_host_alive(&m, 0, clock_us);
        qrtcan_master_bus_error(&m, clock_us);
        recoveries = m.recoveries;
        n_sent = 0;
        recording = 1;
        for (i = 0; i < 12000; i++)
            step(); /* 3 s: three retry periods */
        recording = 0;
        qrtcan_master_get_status(&m, &st);
        CHECK(st.state == QRTCAN_MASTER_FAULT && st.recoveries == recoveries &&
                  n_sent == 0,
              "host not alive: %s, %lu retries, %d SDO/NMT frames",
              qrtcan_master_state_name(st.state), st.recoveries - recoveries,
              n_sent);
        /* the retry waits its full time from alive = 1 on */
        qrtcan_master_set_host_alive(&m, 1, clock_us);
        for (i = 0; i < 3600; i++)
            step();
        CHECK(state() == QRTCAN_MASTER_FAULT && m.recoveries == recoveries,
              "bring-up %.1f s after the host came back",
              (double)STEP_US * i * 1e-6);
        CHECK(run_until(QRTCAN_MASTER_READY, 3.0),
              "no bring-up once the host is alive again");
        CHECK(m.recoveries == recoveries + 1, "%lu retries",
              m.recoveries - recoveries);
    }

    /* the master dies mid-move (its process killed: nothing calls it any
     * more). Drives set up as real ones, with no SYNC watchdog, stop by
     * their heartbeat consumers alone, within the consumer time and a
     * tick of the master's last heartbeat, though they keep hearing each
     * other's */
    {
        static const double kill_move[2][3] = {{0, 0, 0}, {120, 90, -90}};
        uint64_t qs_us[3] = {0, 0, 0};
        long drive_heartbeats = 0;
        power_up(NULL);
        CHECK(run_until(QRTCAN_MASTER_READY, 2.0), "kill: bring-up");
        for (j = 0; j < 3; j++)
            drives[j].watchdog_ms = 0;
        CHECK(qrtcan_master_set_path(&m, kill_move, 2, clock_us) == QRTCAN_OK,
              "kill: path");
        for (i = 0; i < 6000; i++)
            step();
        for (j = 0; j < 3; j++)
            CHECK(drives[j].state == QRTCAN_402_OPERATION_ENABLED &&
                      drives[j].moving && drives[j].vel != 0.0,
                  "kill: drive %d not moving", j + 1);
        for (i = 0; i < 4000; i++) {
            drive_heartbeats += step_drives_only();
            for (j = 0; j < 3; j++)
                if (qs_us[j] == 0 &&
                    drives[j].state == QRTCAN_402_QUICK_STOP_ACTIVE)
                    qs_us[j] = clock_us;
        }
        CHECK(drive_heartbeats >= 3 * 10, "the drives heard %ld heartbeats",
              drive_heartbeats);
        for (j = 0; j < 3; j++) {
            CHECK(qs_us[j] > last_hb_us + 300000u &&
                      qs_us[j] <= last_hb_us + 301000u,
                  "drive %d: quick stop %.2f ms after the master's last "
                  "heartbeat",
                  j + 1, (double)(qs_us[j] - last_hb_us) / 1000.0);
            CHECK(drives[j].vel == 0.0 &&
                      drives[j].state == QRTCAN_402_QUICK_STOP_ACTIVE,
                  "drive %d in %s", j + 1,
                  qrtcan_402_state_name(drives[j].state));
            printf("master killed mid-move: drive %d in Quick Stop Active "
                   "%.2f ms after the master's last heartbeat, %.3f deg "
                   "travelled after it\n",
                   j + 1, (double)(qs_us[j] - last_hb_us) / 1000.0,
                   fabs(drive_deg(j) - hb_deg[j]));
        }
    }

    CHECK(frames_lost == 0, "bus overflow in the test itself");
    return test_done("test_master");
}
