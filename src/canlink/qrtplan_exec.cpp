// qrtplan-exec: execute a saved plan (qrtplan plan -o PLAN.json) on the
// arm's CiA 402 drives over SocketCAN, through the same master the daemon
// uses. Positions are read back from the drives' PDOs; --trace writes them.
#include <array>
#include <cerrno>
#include <csignal>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "can_link.hpp"

extern "C" {
#include "json.h"
#include "qrtplan/qrtplan.h"
}

namespace
{

volatile std::sig_atomic_t interrupted = 0;

void on_signal(int)
{
    interrupted = 1;
}

const char *kUsage =
    "usage: qrtplan-exec --can IFACE PLAN.json [options]\n"
    "       qrtplan-exec --can IFACE --where\n"
    "Moves the arm along PLAN.json's waypoints (a plan from `qrtplan plan`)\n"
    "on three CiA 402 drives in profile position mode; every segment is a\n"
    "straight line in joint space (the joints start and stop together).\n"
    "The arm must stand at the plan's first waypoint (within 1 degree).\n"
    "\n"
    "  --can IFACE          SocketCAN interface (e.g. vcan0, can0)\n"
    "  --nodes A,B,C        drive node ids of alpha, sigma, eta (1,2,3)\n"
    "  --counts-per-deg X[,Y,Z]  drive counts per joint degree: one for\n"
    "                       every joint, or one each (1000)\n"
    "  --offset-counts A[,B,C]  each drive's counts at the joint's 0\n"
    "                       degrees (0)\n"
    "  --speed DEG_S        top joint speed (30); --accel DEG_S2 (60);\n"
    "                       one for every joint, or one each (X,Y,Z)\n"
    "  --timeout S          give up after S seconds (120)\n"
    "  --limits-deg a0,a1,s0,s1,e0,e1  this arm's joint limits; a plan\n"
    "                       with a waypoint outside them is refused\n"
    "                       before the bus opens (docs/spec.md section Arm:\n"
    "                       -180,180,-40,180,-180,140; alpha wraps only\n"
    "                       with -180,180)\n"
    "  --heartbeat-timeout MS  a drive silent this long is lost (300)\n"
    "  --trace FILE         CSV of time and joint positions read back\n"
    "  --where              bring the drives up, print their joints as\n"
    "                       [alpha, sigma, eta] degrees and exit (to plan\n"
    "                       from where the arm stands)\n"
    "  --help               this text\n"
    "  --version            the version\n"
    "Exit status: 0 goal reached, 1 drive/bus fault or timeout, 2 bad input,\n"
    "130 interrupted (the drives get a quick stop).\n";

int fail_input(const std::string &msg)
{
    std::fprintf(stderr, "qrtplan-exec: %s\n", msg.c_str());
    return 2;
}

// The plan's waypoints, or an error message.
std::string read_plan(const std::string &path,
                      std::vector<std::array<double, 3>> *wps)
{
    std::ifstream in(path, std::ios::binary);
    if (!in)
        return path + ": cannot open: " + std::strerror(errno);
    in.peek(); // a directory opens, then cannot be read
    if (in.bad())
        return path + ": cannot read: " + std::strerror(errno);
    std::stringstream ss;
    ss << in.rdbuf();
    std::string text = ss.str();
    char err[200];
    json *root = json_parse(text.data(), text.size(), err, sizeof err);
    if (!root)
        return path + ": " + err;
    std::string why;
    const json *status = json_get(root, "status");
    const json *w = json_get(root, "waypoints_deg");
    if (!status || status->type != JSON_STRING)
        why = "no \"status\" string";
    else if (std::strcmp(status->string, "ok") != 0)
        why = std::string("the plan's status is ") + status->string +
              ", nothing to execute";
    else if (!w || w->type != JSON_ARRAY || w->count < 1 ||
             w->count > QRTCAN_MASTER_MAX_WAYPOINTS)
        why = "\"waypoints_deg\" must be an array of 1.." +
              std::to_string(QRTCAN_MASTER_MAX_WAYPOINTS) + " waypoints";
    for (size_t i = 0; why.empty() && i < w->count; i++) {
        const json &p = w->items[i];
        std::array<double, 3> q{};
        if (p.type != JSON_ARRAY || p.count != 3) {
            why = "waypoint " + std::to_string(i) + " is not [a, s, e]";
            break;
        }
        for (size_t j = 0; j < 3; j++) {
            if (p.items[j].type != JSON_NUMBER) {
                why = "waypoint " + std::to_string(i) + " has a non-number";
                break;
            }
            q[j] = p.items[j].number;
        }
        wps->push_back(q);
    }
    json_free(root);
    return why.empty() ? "" : path + ": " + why;
}

} // namespace

int main(int argc, char **argv)
{
    std::string iface, plan_path, trace_path;
    qrtcan_master_config cfg;
    qrtcan_master_config_default(&cfg);
    double timeout_s = 120.0;
    bool where = false;
    for (int i = 1; i < argc; i++) {
        std::string a = argv[i];
        auto value = [&](const char *name) -> const char * {
            if (i + 1 >= argc) {
                std::fprintf(stderr, "qrtplan-exec: %s needs a value\n", name);
                std::exit(2);
            }
            return argv[++i];
        };
        double v = 0;
        std::string wanted;
        if (a == "--help" || a == "-h") {
            std::fputs(kUsage, stdout);
            return qrt::finish_stdout("qrtplan-exec");
        } else if (a == "--version") {
            std::printf("qrtplan-exec %s\n", QRTPLAN_VERSION);
            return qrt::finish_stdout("qrtplan-exec");
        } else if (a == "--can") {
            iface = value("--can");
        } else if (a == "--nodes") {
            unsigned n[3];
            if (!qrt::parse_node_ids(value("--nodes"), n))
                return fail_input(
                    "--nodes wants three distinct ids in 1..127, e.g. 1,2,3");
            for (int j = 0; j < 3; j++)
                cfg.node[j] = n[j];
        } else if (a.size() > 2 && qrt::is_drive_setting(a.substr(2))) {
            if (!qrt::drive_setting(&cfg, a.substr(2), value(a.c_str()),
                                    &wanted))
                return fail_input(a + " wants " + wanted);
        } else if (a == "--limits-deg") {
            if (!qrt::parse_limits_deg(value(a.c_str()), cfg.limit_deg))
                return fail_input(std::string("--limits-deg wants ") +
                                  qrt::kLimitsDegWanted);
        } else if (a == "--heartbeat-timeout") {
            if (!qrt::parse_numbers(value(a.c_str()), &v, 1) || v < 20 ||
                v > 60000)
                return fail_input("--heartbeat-timeout wants 20..60000 ms");
            cfg.heartbeat_timeout_us = uint32_t(v * 1000.0);
        } else if (a == "--timeout") {
            if (!qrt::parse_numbers(value("--timeout"), &timeout_s, 1) ||
                timeout_s <= 0 || timeout_s > 1e12)
                return fail_input("--timeout wants positive seconds");
        } else if (a == "--where") {
            where = true;
        } else if (a == "--trace") {
            trace_path = value("--trace");
        } else if (!a.empty() && a[0] == '-') {
            return fail_input("unknown option " + a + " (see --help)");
        } else if (plan_path.empty()) {
            plan_path = a;
        } else {
            return fail_input("one plan file only");
        }
    }
    if (iface.empty() || (plan_path.empty() && !where))
        return fail_input("need --can IFACE and a PLAN.json (see --help)");
    std::vector<std::array<double, 3>> wps;
    std::string why = where ? "" : read_plan(plan_path, &wps);
    if (!why.empty())
        return fail_input(why);
    int outside = qrt::path_outside_limits(cfg, wps);
    if (outside >= 0) {
        const auto &w = wps[size_t(outside)];
        return fail_input(plan_path + ": waypoint " + std::to_string(outside) +
                          " (" + std::to_string(w[0]) + ", " +
                          std::to_string(w[1]) + ", " + std::to_string(w[2]) +
                          ") is outside the joint limits (--limits-deg), or "
                          "alpha steps more than 180 degrees to it");
    }
    FILE *trace = nullptr;
    if (!trace_path.empty() && !(trace = std::fopen(trace_path.c_str(), "w")))
        return fail_input(trace_path + ": " + std::strerror(errno));
    if (trace)
        std::fprintf(trace, "t_s,alpha_deg,sigma_deg,eta_deg,state,waypoint\n");

    std::signal(SIGINT, on_signal);
    std::signal(SIGTERM, on_signal);
    qrt::CanLink link(iface, cfg);
    if (!link.start(&why))
        return fail_input(why);
    const uint64_t t0 = qrt::CanLink::now_us();
    const uint64_t deadline = t0 + uint64_t(timeout_s * 1e6);
    bool sent = false;
    int rc = 1;
    std::string last_link;
    while (!interrupted) {
        qrt::CanLinkStatus st = link.status();
        uint64_t now = qrt::CanLink::now_us();
        if (st.link != last_link) {
            std::fprintf(stderr, "qrtplan-exec: %s: %s\n", iface.c_str(),
                         st.link.c_str());
            last_link = st.link;
        }
        if (trace && st.master.all_positions_known)
            std::fprintf(trace, "%.4f,%.6f,%.6f,%.6f,%s,%d\n",
                         double(now - t0) * 1e-6, st.master.joints_deg[0],
                         st.master.joints_deg[1], st.master.joints_deg[2],
                         qrtcan_master_state_name(st.master.state),
                         st.master.waypoint);
        if (st.master.state == QRTCAN_MASTER_FAULT) {
            std::fprintf(stderr,
                         "qrtplan-exec: stopped: %s (node %u, code 0x%04x)\n",
                         qrtcan_master_reason_name(st.master.reason),
                         st.master.reason_node, st.master.reason_code);
            rc = 1;
            break;
        }
        if (where && st.master.state == QRTCAN_MASTER_READY &&
            st.master.all_positions_known) {
            std::printf("[%.6f, %.6f, %.6f]\n", st.master.joints_deg[0],
                        st.master.joints_deg[1], st.master.joints_deg[2]);
            rc = 0;
            break;
        }
        if (!where && !sent && st.master.state == QRTCAN_MASTER_READY) {
            int r = link.set_path(wps);
            if (r == QRTCAN_E_RANGE) { // the limits were checked above
                std::fprintf(stderr,
                             "qrtplan-exec: the arm stands at (%.3f, %.3f, "
                             "%.3f), the plan starts at (%.3f, %.3f, %.3f): "
                             "plan from the arm's joints\n",
                             st.master.joints_deg[0], st.master.joints_deg[1],
                             st.master.joints_deg[2], wps[0][0], wps[0][1],
                             wps[0][2]);
                rc = 2;
                break;
            }
            if (r != QRTCAN_OK) {
                std::fprintf(stderr, "qrtplan-exec: path refused: %s\n",
                             qrtcan_strerror(r));
                rc = 1;
                break;
            }
            sent = true;
        } else if (sent && st.master.state == QRTCAN_MASTER_READY &&
                   st.master.path_done) {
            std::printf("goal reached: %.4f %.4f %.4f deg\n",
                        st.master.joints_deg[0], st.master.joints_deg[1],
                        st.master.joints_deg[2]);
            rc = 0;
            break;
        }
        if (now > deadline) {
            std::fprintf(stderr, "qrtplan-exec: timeout in state %s\n",
                         qrtcan_master_state_name(st.master.state));
            link.quick_stop();
            rc = 1;
            break;
        }
        std::this_thread::sleep_for(std::chrono::milliseconds(5));
    }
    if (interrupted) {
        link.quick_stop();
        std::fprintf(stderr, "qrtplan-exec: interrupted: quick stop sent\n");
        rc = 130;
    }
    if (trace)
        std::fclose(trace);
    return rc;
}
