/* servo_sim: simulated CiA 402 drives on a SocketCAN interface. The drive
 * logic is drive.c (portable); this file is the board: options, the
 * SocketCAN driver, the 1 ms loop, and faults injected on schedule. */
#define _POSIX_C_SOURCE 200809L
#include <errno.h>
#include <math.h>
#include <signal.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "args.h"
#include "drive.h"
#include "qrtcan/emcy.h"
#include "qrtcan/frame.h"
#include "qrtplan/joints.h"
#include "socketcan.h"

#define MAX_DRIVES 8
#define TICK_US 1000u
/* frames a loop takes before the drives tick: 8 times what a 1 Mbit/s bus
 * carries in a tick */
#define MAX_FRAMES_PER_TICK 64

static volatile sig_atomic_t stop_requested;

static void on_signal(int sig)
{
    (void)sig;
    stop_requested = 1;
}

static void usage(FILE *out)
{
    fputs(
        "usage: servo_sim [options]\n"
        "Simulated CiA 402 servo drives (profile position mode) on SocketCAN.\n"
        "\n"
        "  --iface NAME          CAN interface (default vcan0)\n"
        "  --nodes A,B,...       node ids, up to 8 (default 1,2,3: joints\n"
        "                        alpha, sigma, eta)\n"
        "  --counts-per-deg X[,Y,Z]  scale behind the default position limits\n"
        "                        and --start-deg, one for every joint or one\n"
        "                        each (the drives past the third take Z)\n"
        "                        (default 1000; limits are the arm's joint\n"
        "                        limits [-40,180] and [-180,140] deg for "
        "sigma\n"
        "                        and eta; alpha wraps, so its drive turns\n"
        "                        without a limit)\n"
        "  --offset-counts A[,B,C]  each drive's counts at its joint's 0\n"
        "                        degrees, one for every joint or one each\n"
        "                        (default 0; past the third, C): for\n"
        "                        --start-deg and the default limits\n"
        "  --start-deg A,S,E     the first three drives' positions at "
        "power-up,\n"
        "                        in degrees (default 0,0,0)\n"
        "  --limit ID:MIN:MAX    position limits of node ID (one of --nodes)\n"
        "                        in counts, 32-bit signed (0x607D)\n"
        "  --servo-error COUNTS  steady-state error: every drive settles at\n"
        "                        target + COUNTS (0x2001, default 0)\n"
        "  --heartbeat-ms MS     heartbeat producer time (0x1017, default "
        "100)\n"
        "  --watchdog-ms MS      vendor SYNC watchdog (0x2000): no SYNC for "
        "MS\n"
        "                        while operational -> EMCY 0x8130 and the\n"
        "                        reaction of 0x6007 (default 500; 0 = off);\n"
        "                        heartbeats do not feed it\n"
        "  --fault-at SECONDS    inject a drive fault SECONDS after start\n"
        "  --fault-node ID       which node faults (default the first)\n"
        "  --fault-code HEX      its EMCY error code (default 0x2310, over "
        "current)\n"
        "  --mute-node ID        node ID goes silent (sends and answers "
        "nothing)\n"
        "  --mute-at SECONDS     ... from SECONDS after start (default 0)\n"
        "  --duration SECONDS    exit after SECONDS (default: run until "
        "SIGINT\n"
        "                        or SIGTERM)\n"
        "  --verbose             log every CiA 402 state change on stderr\n"
        "  --help                this text\n"
        "  --version             the version\n"
        "\n"
        "Heartbeat consumer (0x1016:1..4, CiA 301): empty at power-up, as on\n"
        "real drives; an entry is (node id << 16) | time in ms, written by "
        "the\n"
        "master over SDO. Once the entry's node has sent a heartbeat, none "
        "from\n"
        "that node for the time -> EMCY 0x8130 and, in Operation Enabled or\n"
        "Quick Stop Active, the abort connection option (0x6007: 0 no action,\n"
        "1 fault, 2 disable voltage, 3 quick stop, the default). Only the\n"
        "entry's node feeds it, never another drive's heartbeat.\n"
        "\n"
        "Object dictionary, PDO mapping and EMCY codes: can/servo_sim.eds and\n"
        "firmware_sim/README.md.\n",
        out);
}

static int is_simulated(const unsigned *nodes, unsigned n_nodes, long id)
{
    unsigned j;
    for (j = 0; j < n_nodes; j++) {
        if ((long)nodes[j] == id) {
            return 1;
        }
    }
    return 0;
}

static const char *state_name(enum qrtcan_402_state s)
{
    return qrtcan_402_state_name(s);
}

int main(int argc, char **argv)
{
    static struct drive drives[MAX_DRIVES];
    struct drive_config cfg[MAX_DRIVES];
    unsigned nodes[MAX_DRIVES] = {1, 2, 3}, n_nodes = 3, i;
    static const double lim_deg[3][2] = QRT_ARM_DEFAULT_LIMIT_DEG;
    double start_deg[3] = {0, 0, 0};
    const char *iface = "vcan0";
    double counts_per_deg[3] = {1000, 1000, 1000}, offset_counts[3] = {0, 0, 0};
    double fault_at = -1, mute_at = 0, duration = 0;
    long servo_error = 0, heartbeat_ms = 100, watchdog_ms = 500;
    long fault_node = 0, fault_code = QRTCAN_EMCY_OVERCURRENT, mute_node = 0;
    long lim_id[MAX_DRIVES];
    long lim_min[MAX_DRIVES], lim_max[MAX_DRIVES];
    unsigned n_lim = 0;
    int verbose = 0, fault_done = 0, bus_down = 0, a;
    struct socketcan sc;
    struct can_driver can;
    uint64_t start, next_tick, t;
    enum qrtcan_402_state seen[MAX_DRIVES];

    for (a = 1; a < argc; a++) {
        const char *o = argv[a], *v = a + 1 < argc ? argv[a + 1] : 0;
        int bad = 0;
        if (strcmp(o, "--help") == 0 || strcmp(o, "-h") == 0) {
            usage(stdout);
            return args_finish_stdout("servo_sim");
        }
        if (strcmp(o, "--version") == 0) {
            printf("servo_sim %s\n", QRT_VERSION);
            return args_finish_stdout("servo_sim");
        }
        if (strcmp(o, "--verbose") == 0) {
            verbose = 1;
            continue;
        }
        if (v == 0) {
            fprintf(stderr, "servo_sim: %s needs a value (see --help)\n", o);
            return 2;
        }
        a++;
        if (strcmp(o, "--iface") == 0) {
            iface = v;
        } else if (strcmp(o, "--nodes") == 0) {
            bad = qrtcan_parse_node_list(v, nodes, MAX_DRIVES, &n_nodes) != 0;
        } else if (strcmp(o, "--counts-per-deg") == 0) {
            bad = args_per_joint(v, 1e-6, 999999.0, counts_per_deg);
        } else if (strcmp(o, "--offset-counts") == 0) {
            bad = args_per_joint(v, -1e9, 1e9, offset_counts) ||
                  offset_counts[0] != floor(offset_counts[0]) ||
                  offset_counts[1] != floor(offset_counts[1]) ||
                  offset_counts[2] != floor(offset_counts[2]);
        } else if (strcmp(o, "--start-deg") == 0) {
            bad = args_numbers(v, 3, -1e5, 1e5, start_deg);
        } else if (strcmp(o, "--limit") == 0) {
            /* 0x607D's limits are INTEGER32: a wider value would wrap */
            char extra;
            bad = n_lim == MAX_DRIVES ||
                  sscanf(v, "%ld:%ld:%ld%c", &lim_id[n_lim], &lim_min[n_lim],
                         &lim_max[n_lim], &extra) != 3 ||
                  lim_id[n_lim] < 1 || lim_id[n_lim] > 127 ||
                  lim_min[n_lim] < INT32_MIN || lim_max[n_lim] > INT32_MAX ||
                  lim_min[n_lim] > lim_max[n_lim];
            n_lim += !bad;
        } else if (strcmp(o, "--servo-error") == 0) {
            bad = args_long(v, 0, -1000000, 1000000, &servo_error);
        } else if (strcmp(o, "--heartbeat-ms") == 0) {
            bad = args_long(v, 0, 0, 65535, &heartbeat_ms);
        } else if (strcmp(o, "--watchdog-ms") == 0) {
            bad = args_long(v, 0, 0, 3600000, &watchdog_ms);
        } else if (strcmp(o, "--fault-at") == 0) {
            bad = args_number(v, 0, 1e6, &fault_at);
        } else if (strcmp(o, "--fault-node") == 0) {
            bad = args_long(v, 0, 1, 127, &fault_node);
        } else if (strcmp(o, "--fault-code") == 0) {
            bad = args_long(v, 0, 1, 0xFFFF, &fault_code);
        } else if (strcmp(o, "--mute-node") == 0) {
            bad = args_long(v, 0, 1, 127, &mute_node);
        } else if (strcmp(o, "--mute-at") == 0) {
            bad = args_number(v, 0, 1e6, &mute_at);
        } else if (strcmp(o, "--duration") == 0) {
            bad = args_number(v, 0, 1e6, &duration);
        } else {
            fprintf(stderr, "servo_sim: unknown option %s (see --help)\n", o);
            return 2;
        }
        if (bad) {
            fprintf(stderr, "servo_sim: bad value for %s: %s\n", o, v);
            return 2;
        }
    }

    /* an option naming a node that is not simulated would silently do
     * nothing: a fault test would wait for a fault that never comes */
    for (i = 0; i < n_lim; i++) {
        if (!is_simulated(nodes, n_nodes, lim_id[i])) {
            fprintf(stderr, "servo_sim: --limit for node %ld, not in --nodes\n",
                    lim_id[i]);
            return 2;
        }
    }
    if (fault_node != 0 && !is_simulated(nodes, n_nodes, fault_node)) {
        fprintf(stderr, "servo_sim: --fault-node %ld, not in --nodes\n",
                fault_node);
        return 2;
    }
    if (mute_node != 0 && !is_simulated(nodes, n_nodes, mute_node)) {
        fprintf(stderr, "servo_sim: --mute-node %ld, not in --nodes\n",
                mute_node);
        return 2;
    }
    /* the power-up positions in counts must fit 0x6064's INTEGER32 */
    for (i = 0; i < 3; i++) {
        if (!(fabs(offset_counts[i] + start_deg[i] * counts_per_deg[i]) <
              2.0e9)) {
            fprintf(stderr,
                    "servo_sim: --start-deg %g times --counts-per-deg %g "
                    "(from %g at 0 degrees) is beyond a 32-bit position\n",
                    start_deg[i], counts_per_deg[i], offset_counts[i]);
            return 2;
        }
    }
    if (socketcan_open(&sc, iface, &can) != 0) {
        return 1;
    }
    signal(SIGINT, on_signal);
    signal(SIGTERM, on_signal);
    for (i = 0; i < n_nodes; i++) {
        unsigned j, k = i < 3 ? i : 2;
        memset(&cfg[i], 0, sizeof cfg[i]);
        cfg[i].node = nodes[i];
        cfg[i].limit_min =
            (int32_t)(offset_counts[k] + lim_deg[k][0] * counts_per_deg[k]);
        cfg[i].limit_max =
            (int32_t)(offset_counts[k] + lim_deg[k][1] * counts_per_deg[k]);
        if (k == 0 && qrt_alpha_wraps(lim_deg[0])) { /* no end stops */
            cfg[i].limit_min = INT32_MIN;
            cfg[i].limit_max = INT32_MAX;
        }
        if (i < 3) {
            double c = offset_counts[i] + start_deg[i] * counts_per_deg[i];
            cfg[i].start_position = (int32_t)(c < 0 ? c - 0.5 : c + 0.5);
        }
        for (j = 0; j < n_lim; j++) {
            if ((unsigned long)lim_id[j] == nodes[i]) {
                cfg[i].limit_min = (int32_t)lim_min[j];
                cfg[i].limit_max = (int32_t)lim_max[j];
            }
        }
        cfg[i].servo_error = (int32_t)servo_error;
        cfg[i].watchdog_ms = (uint32_t)watchdog_ms;
        cfg[i].heartbeat_ms = (uint16_t)heartbeat_ms;
        drive_init(&drives[i], &cfg[i], &can);
        seen[i] = drives[i].state;
    }
    if (fault_node == 0) {
        fault_node = (long)nodes[0];
    }
    fprintf(stderr, "servo_sim: %u drive(s) on %s\n", n_nodes, iface);

    start = can.now_us(can.ctx);
    next_tick = start + TICK_US;
    while (!stop_requested) {
        struct qrtcan_frame f;
        double elapsed;
        int rc, drained;
        t = can.now_us(can.ctx);
        rc = can.receive(can.ctx, &f,
                         next_tick > t ? (uint32_t)(next_tick - t) : 0u);
        if (rc < 0) {
            /* an interface that goes down is a silent bus to firmware: the
             * drives go on (their watchdogs notice), and so does the loop */
            if (!bus_down)
                fprintf(stderr,
                        "servo_sim: receive: %s (the drives see a "
                        "silent bus until it comes back)\n",
                        strerror(errno));
            bus_down = 1;
            nanosleep(&(struct timespec){0, 1000000}, NULL);
            rc = 0;
        } else if (rc == 1 && bus_down) {
            fprintf(stderr, "servo_sim: the bus is back\n");
            bus_down = 0;
        }
        /* Every frame already received reaches the drives before their
         * motors move on: on a real bus the three set-points sent in a row
         * reach their drives within a few hundred microseconds, and a
         * simulator descheduled between reading them must not let one joint
         * run ahead of the others for a whole tick (0.73 deg once, in a VM
         * on a loaded host). Bounded, so a flood cannot stall the ticks. */
        for (drained = 0; rc == 1;) {
            for (i = 0; i < n_nodes; i++) {
                drive_on_frame(&drives[i], &f, &can);
            }
            if (++drained == MAX_FRAMES_PER_TICK)
                break;
            rc = can.receive(can.ctx, &f, 0u) == 1;
        }
        t = can.now_us(can.ctx);
        if (t < next_tick) {
            continue;
        }
        next_tick += TICK_US;
        if (next_tick < t) {
            next_tick = t + TICK_US; /* fell behind: do not burst */
        }
        elapsed = (double)(t - start) * 1e-6;
        for (i = 0; i < n_nodes; i++) {
            struct drive *d = &drives[i];
            if (mute_node == (long)d->cfg.node && elapsed >= mute_at &&
                !d->muted) {
                d->muted = 1;
                fprintf(stderr, "servo_sim: node %u muted\n", d->cfg.node);
            }
            if (!fault_done && fault_at >= 0 && elapsed >= fault_at &&
                fault_node == (long)d->cfg.node) {
                fault_done = 1;
                fprintf(stderr, "servo_sim: node %u fault 0x%04lX injected\n",
                        d->cfg.node, fault_code);
                drive_fault(d, (uint16_t)fault_code, &can);
            }
            drive_tick(d, &can);
            if (verbose && d->state != seen[i]) {
                fprintf(stderr, "servo_sim: node %u %s -> %s (pos %ld)\n",
                        d->cfg.node, state_name(seen[i]), state_name(d->state),
                        (long)d->position_actual);
            }
            seen[i] = d->state;
        }
        if (duration > 0 && elapsed >= duration) {
            break;
        }
    }
    if (sc.dropped) {
        fprintf(stderr, "servo_sim: %lu frames dropped by the kernel\n",
                sc.dropped);
    }
    socketcan_close(&sc);
    return 0;
}
