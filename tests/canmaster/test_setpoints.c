/* qrtplan setpoints' CSV against the motion the CiA 402 master
 * (src/canmaster) makes three simulated drives (firmware_sim/drive.c) do
 * on the same path: the profile writes it sends equal qrtcan/profile.h's
 * for the path's segments, and the drives' positions at each row's time
 * (counted from the segment's set-point, as the master pauses between
 * segments for its SDO round trips) equal the row's. Also: the first and
 * last rows are the plan's waypoints, no row pair passes a joint's speed
 * or acceleration, and every moving joint reaches each waypoint on the
 * same row (in the drives: within a step of each other). */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "../../firmware_sim/drive.h"
#include "../unit/check.h"
#include "mem_bus.h"
#include "qrtcan/master.h"
#include "qrtcan/profile.h"
#include "qrtcan/sdo.h"
#include "setpoints.h"

/* the world's step: the drives integrate their trapezoid over it, so the
 * simulation strays from the exact trapezoid by about accel * step * t */
#define STEP_US 20u
#define MAX_ROWS 20000
#define MAX_SEG 8

static struct drive drives[3];
static struct qrtcan_master m;
/* the profile writes the master sent: [segment][joint][0x6081, 83, 84] */
static uint32_t sent_profile[MAX_SEG][3][3];
static int sent_seen[MAX_SEG][3][3];

static void observe(const struct qrtcan_frame *f)
{
    struct qrtcan_sdo s;
    unsigned node;
    int k;
    if (qrtcan_sdo_decode_request(f, &node, &s) != QRTCAN_OK ||
        s.type != QRTCAN_SDO_WRITE || node < 1 || node > 3 ||
        m.waypoint >= MAX_SEG)
        return;
    k = s.index == 0x6081   ? 0
        : s.index == 0x6083 ? 1
        : s.index == 0x6084 ? 2
                            : -1;
    if (k < 0)
        return;
    sent_profile[m.waypoint][node - 1][k] = s.data;
    sent_seen[m.waypoint][node - 1][k] = 1;
}

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
    for (j = 0; j < 3; j++)
        drive_tick(&drives[j], &can);
    for (i = 0; i < bus_count; i++) {
        qrtcan_master_on_frame(&m, &bus[i], clock_us);
        for (j = 0; j < 3; j++)
            drive_on_frame(&drives[j], &bus[i], &can);
    }
    bus_count = 0;
}

static double rows[MAX_ROWS][4];
static int n_rows;

/* The CSV setpoints_write gives for the path, read back. */
static void csv_rows(const double (*wp)[3], int n,
                     const struct setpoint_options *o)
{
    char err[256], line[512];
    FILE *f = tmpfile();
    CHECK(f != NULL, "tmpfile");
    if (!f)
        exit(1);
    CHECK(setpoints_write(f, wp, n, o, err, sizeof err) == 0, "write: %s", err);
    rewind(f);
    CHECK(fgets(line, sizeof line, f) &&
              strcmp(line, "t_s,alpha_deg,sigma_deg,eta_deg\n") == 0,
          "header %s", line);
    n_rows = 0;
    while (n_rows < MAX_ROWS && fgets(line, sizeof line, f)) {
        double *r = rows[n_rows];
        CHECK(sscanf(line, "%lf,%lf,%lf,%lf", &r[0], &r[1], &r[2], &r[3]) == 4,
              "row %d: %s", n_rows, line);
        n_rows++;
    }
    fclose(f);
}

/* One path: drives at wp[0], speeds and accelerations per joint. */
static void run_path(const char *name, const double (*wp)[3], int n,
                     const double speed[3], const double accel[3])
{
    struct qrtcan_master_config cfg;
    struct setpoint_options o;
    struct qrtcan_segment seg[MAX_SEG];
    double from[3], t_seg[MAX_SEG + 1], sim_start[MAX_SEG];
    double prev_pos[3], worst = 0.0, worst_sync = 0.0, worst_pause = 0.0;
    double arrive[MAX_SEG][3];
    int i, j, k, row, started[MAX_SEG], last_wp = -1, last_phase = -1;
    uint64_t prev_clock, end;

    /* the CSV, and the segments it is made of */
    setpoints_default(&o);
    for (j = 0; j < 3; j++) {
        o.speed_deg_s[j] = speed[j];
        o.accel_deg_s2[j] = accel[j];
    }
    csv_rows(wp, n, &o);
    memcpy(from, wp[0], sizeof from);
    t_seg[1] = 0.0;
    for (k = 1; k < n; k++) {
        double stp[3];
        qrtcan_segment_step(from, wp[k], stp);
        CHECK(qrtcan_segment_profile(speed, accel, stp, &seg[k]) == QRTCAN_OK,
              "profile");
        t_seg[k + 1] = t_seg[k] + seg[k].duration_s;
        for (j = 0; j < 3; j++)
            from[j] += stp[j];
        started[k] = 0;
        for (j = 0; j < 3; j++)
            arrive[k][j] = -1.0;
    }

    /* the master and its drives, brought up at wp[0] */
    memset(drives, 0, sizeof drives);
    memset(sent_seen, 0, sizeof sent_seen);
    bus_count = 0;
    qrtcan_master_config_default(&cfg);
    for (j = 0; j < 3; j++) {
        struct drive_config dc;
        memset(&dc, 0, sizeof dc);
        dc.node = (unsigned)j + 1;
        dc.limit_min = -400000;
        dc.limit_max = 400000;
        dc.servo_error = 0; /* lands on the target: the next step is exact */
        dc.watchdog_ms = 200;
        dc.start_position = (int32_t)lround(wp[0][j] * 1000.0);
        drive_init(&drives[j], &dc, &can);
        cfg.max_speed_deg_s[j] = speed[j];
        cfg.max_accel_deg_s2[j] = accel[j];
    }
    CHECK(qrtcan_master_init(&m, &cfg, clock_us) == QRTCAN_OK, "init");
    qrtcan_master_start(&m, clock_us);
    for (i = 0; i < 200000 && m.state != QRTCAN_MASTER_READY; i++)
        step();
    CHECK(m.state == QRTCAN_MASTER_READY, "%s: not ready", name);
    CHECK(qrtcan_master_set_path(&m, wp, n, clock_us) == QRTCAN_OK,
          "%s: path refused", name);

    /* run it; each row's time, counted from its segment's set-point */
    row = 0;
    for (j = 0; j < 3; j++)
        prev_pos[j] = drives[j].pos / 1000.0;
    prev_clock = clock_us;
    end = clock_us + 60000000u;
    while (clock_us < end && !(m.state == QRTCAN_MASTER_READY && m.path_done)) {
        step();
        CHECK(m.state != QRTCAN_MASTER_FAULT, "%s: fault", name);
        if (m.state == QRTCAN_MASTER_FAULT)
            return;
        /* the set-point went out in this step, and the drives moved over
         * it: the segment began a step ago */
        if (m.state == QRTCAN_MASTER_MOVING && m.segment_phase == 1 &&
            (last_phase != 1 || last_wp != m.waypoint) &&
            m.waypoint < MAX_SEG) {
            started[m.waypoint] = 1;
            sim_start[m.waypoint] = (double)(clock_us - STEP_US) * 1e-6;
        }
        last_phase = m.state == QRTCAN_MASTER_MOVING ? m.segment_phase : -1;
        last_wp = m.waypoint;
        /* each drive's arrival: its goal reached in this step */
        for (k = 1; k < n; k++)
            for (j = 0; j < 3; j++)
                if (started[k] && arrive[k][j] < 0.0 &&
                    fabs(seg[k].step_deg[j]) >= 1e-9 && !drives[j].moving &&
                    (k + 1 >= n || !started[k + 1]))
                    arrive[k][j] = (double)clock_us * 1e-6 - sim_start[k];
        /* the rows whose moment this step passed */
        while (row < n_rows) {
            double t = rows[row][0], when, a;
            for (k = 1; k + 1 < n && t >= t_seg[k + 1]; k++)
                ;
            if (n < 2 || !started[k])
                break;
            when = sim_start[k] + (t - t_seg[k]);
            if (when > (double)clock_us * 1e-6)
                break;
            a = (when - (double)prev_clock * 1e-6) / (STEP_US * 1e-6);
            for (j = 0; j < 3; j++) {
                double p =
                    prev_pos[j] + a * (drives[j].pos / 1000.0 - prev_pos[j]);
                double e = fabs(p - rows[row][1 + j]);
                if (e > worst)
                    worst = e;
            }
            row++;
        }
        for (j = 0; j < 3; j++)
            prev_pos[j] = drives[j].pos / 1000.0;
        prev_clock = clock_us;
    }
    CHECK(m.path_done, "%s: path not done", name);
    /* the rest of the rows: the drives stand at the goal */
    for (; row < n_rows; row++)
        for (j = 0; j < 3; j++)
            if (fabs(drives[j].pos / 1000.0 - rows[row][1 + j]) > worst)
                worst = fabs(drives[j].pos / 1000.0 - rows[row][1 + j]);
    /* positions: within one count (0.001 deg; the simulation's own
     * integration error over its 20 us steps is 0.0003 deg) */
    CHECK(worst < 0.001, "%s: the drives strayed %g deg from the CSV", name,
          worst);

    /* the frames: the master's profile writes are the library's */
    for (k = 1; k < n && k < MAX_SEG; k++) {
        uint32_t vel[3], acc[3];
        qrtcan_segment_counts(&seg[k], cfg.scale, vel, acc);
        for (j = 0; j < 3; j++)
            CHECK(sent_seen[k][j][0] && sent_seen[k][j][1] &&
                      sent_seen[k][j][2] && sent_profile[k][j][0] == vel[j] &&
                      sent_profile[k][j][1] == acc[j] &&
                      sent_profile[k][j][2] == acc[j],
                  "%s: segment %d joint %d sent %u/%u/%u, profile %u/%u", name,
                  k, j, (unsigned)sent_profile[k][j][0],
                  (unsigned)sent_profile[k][j][1],
                  (unsigned)sent_profile[k][j][2], (unsigned)vel[j],
                  (unsigned)acc[j]);
    }

    /* the first and last rows: the waypoints (alpha continuous, so the last
     * may be a turn away) */
    CHECK(n_rows >= 1 && rows[0][0] == 0.0 && rows[0][1] == wp[0][0] &&
              rows[0][2] == wp[0][1] && rows[0][3] == wp[0][2],
          "%s: first row", name);
    CHECK(fabs(fmod(rows[n_rows - 1][1] - wp[n - 1][0] + 540.0, 360.0) -
               180.0) < 1e-9 &&
              rows[n_rows - 1][2] == wp[n - 1][1] &&
              rows[n_rows - 1][3] == wp[n - 1][2] &&
              fabs(rows[n_rows - 1][0] - t_seg[n]) < 1e-9,
          "%s: last row %g: %g %g %g", name, rows[n_rows - 1][0],
          rows[n_rows - 1][1], rows[n_rows - 1][2], rows[n_rows - 1][3]);

    /* limits: speed between rows, acceleration over three (uneven at the
     * end) */
    for (i = 1; i < n_rows; i++)
        for (j = 0; j < 3; j++) {
            double dt = rows[i][0] - rows[i - 1][0];
            double v = (rows[i][1 + j] - rows[i - 1][1 + j]) / dt;
            CHECK(dt > 0.0 && fabs(v) <= speed[j] * (1 + 1e-6) + 1e-6,
                  "%s: row %d joint %d at %g deg/s", name, i, j, v);
            if (i >= 2) {
                double dt0 = rows[i - 1][0] - rows[i - 2][0];
                double v0 = (rows[i - 1][1 + j] - rows[i - 2][1 + j]) / dt0;
                double acc = (v - v0) / (0.5 * (dt + dt0));
                CHECK(fabs(acc) <= accel[j] * (1 + 1e-6) + 1e-4,
                      "%s: row %d joint %d at %g deg/s^2", name, i, j, acc);
            }
        }

    /* together: each segment's moving joints reach their waypoint on the
     * same row of the CSV, and in the drives within two steps */
    for (k = 1; k < n; k++) {
        int first_row[3];
        double lo = 1e9, hi = -1e9;
        for (j = 0; j < 3; j++) {
            double target = rows[0][1 + j];
            int r;
            first_row[j] = -1;
            if (fabs(seg[k].step_deg[j]) < 1e-9)
                continue;
            for (i = 1; i <= k; i++)
                target += seg[i].step_deg[j];
            for (r = 0; r < n_rows; r++)
                if (rows[r][0] > t_seg[k] - 1e-12 &&
                    fabs(rows[r][1 + j] - target) < 1e-9) {
                    first_row[j] = r;
                    break;
                }
            if (arrive[k][j] < lo)
                lo = arrive[k][j];
            if (arrive[k][j] > hi)
                hi = arrive[k][j];
        }
        for (j = 0; j < 3; j++)
            for (i = 0; i < 3; i++)
                CHECK(first_row[j] < 0 || first_row[i] < 0 ||
                          first_row[j] == first_row[i],
                      "%s: segment %d: joint %d arrives on row %d, joint "
                      "%d on row %d",
                      name, k, j, first_row[j], i, first_row[i]);
        if (hi - lo > worst_sync)
            worst_sync = hi - lo;
        CHECK(hi - lo <= 2.5 * STEP_US * 1e-6 &&
                  fabs(hi - seg[k].duration_s) < 0.01,
              "%s: segment %d: drives arrive %g..%g s in, the profile %g s",
              name, k, lo, hi, seg[k].duration_s);
    }
    /* the master's pause between segments (not in the CSV): SDO round
     * trips and the set-point handshake, a few SYNC periods */
    for (k = 1; k + 1 < n; k++) {
        double pause = sim_start[k + 1] - sim_start[k] - seg[k].duration_s;
        if (pause > worst_pause)
            worst_pause = pause;
    }
    printf("%s: %d rows, %.3f s; drives within %.4f deg of the rows, "
           "arrivals within %.0f us; the master pauses up to %.1f ms "
           "between segments\n",
           name, n_rows, t_seg[n], worst, worst_sync * 1e6, worst_pause * 1e3);
}

int main(void)
{
    /* trapezoids, alpha across +-180, and a triangle (a step too short to
     * reach the speed) */
    static const double path1[5][3] = {{-100, 0, 0},
                                       {-175, -20, 10},
                                       {145, -15, 10.5},
                                       {100, 0, -30},
                                       {104, 2, -28}};
    static const double equal[3] = {30, 30, 30}, equal_a[3] = {60, 60, 60};
    /* joints rated differently: the slowest sets each segment's pace */
    static const double rated[3] = {40, 10, 20}, rated_a[3] = {80, 20, 40};
    static const double path2[3][3] = {{0, 0, 0}, {20, 10, -15}, {-10, 35, 5}};
    run_path("path across 180", path1, 5, equal, equal_a);
    run_path("joints rated differently", path2, 3, rated, rated_a);
    CHECK(frames_lost == 0, "bus overflow in the test itself");
    return test_done("test_setpoints");
}
