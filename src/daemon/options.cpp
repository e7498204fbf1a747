#include "options.hpp"

#include "can_link.hpp"
#include "keyfile.hpp"
#include "qrtplan/qrtplan.h"

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <map>
#include <sstream>
#include <vector>

namespace qrt
{

const char *kUsage =
    "usage: qrtpland [--config FILE] [options]\n"
    "The qrtplan daemon: turns range scans into obstacle points, replans on\n"
    "every scan towards the newest plan request, and publishes plans, the\n"
    "joint state and a 1 Hz status on LCM. With --can it drives the arm's\n"
    "three CiA 402 drives and stops them when a scan blocks the path being\n"
    "executed.\n"
    "\n"
    "Options (also as `key = value` lines in the config file, without --,\n"
    "each at most once there):\n"
    "  --lcm-url URL            (udpm://239.255.76.67:7667?ttl=0)\n"
    "  --scan-channel NAME      scans on NAME and NAME_* (QRT_SCAN); each\n"
    "                           sensor_id keeps its own entry\n"
    "  --cloud-channel NAME     point clouds on NAME and NAME_* (QRT_CLOUD),\n"
    "                           taken as scans are (a sensor_id's newest\n"
    "                           scan or cloud is its entry)\n"
    "  --request-channel NAME   plan requests (QRT_PLAN_REQUEST)\n"
    "  --plan-channel NAME      plans out (QRT_PLAN)\n"
    "  --joint-channel NAME     joint state: published with --can, else\n"
    "                           read from the drives' publisher "
    "(QRT_JOINT_STATE)\n"
    "  --status-channel NAME    1 Hz daemon status (QRT_STATUS)\n"
    "                           (channel names: 1..63 of A-Z a-z 0-9 _ - / :)\n"
    "  --window SECONDS         obstacle picture = every scan of the last\n"
    "                           SECONDS per sensor (0: the latest scan only)\n"
    "  --mask as-read|whole     find only the mask nodes the plan reads,\n"
    "                           as it reads them, or the whole mask first\n"
    "                           (as-read; the plan is the same)\n"
    "  --mask-threads 1|2       build a whole mask on 1 or 2 threads (2)\n"
    "  --max-returns N          refuse scans (clouds) with more returns\n"
    "                           (points) (1000000)\n"
    "  --max-points N           points the obstacle picture holds, all\n"
    "                           sensors together (2000000); returns beyond\n"
    "                           the arm's reach are dropped first; a scan\n"
    "                           that does not fit beside every other\n"
    "                           sensor's newest is refused\n"
    "  --require-sensor ID[,ID...]  a sensor every plan and every motion\n"
    "                           needs a fresh scan from (repeatable; none:\n"
    "                           any one sensor's fresh scan will do)\n"
    "  --sensor ID[,ID...]      a further sensor taken but not required\n"
    "                           (repeatable); with either list, scans from\n"
    "                           sensors on neither are refused\n"
    "  --max-scan-age SECONDS   evidence older than this is none: plans say\n"
    "                           stale_obstacle_data and the arm stops (0.5)\n"
    "  --max-clock-skew SECONDS a scan stamped further ahead of this\n"
    "                           computer's clock is refused (0.05)\n"
    "  --guard-deadline MS      with --can, the guard thread silent this\n"
    "                           long stops the arm and the CAN heartbeat\n"
    "                           (200)\n"
    "  --planner-deadline MS    likewise for the planner thread (2000)\n"
    "  --margin M               workspace margin, metres (0.01)\n"
    "  --cspace-margin DEG      C-space margin (paper Eq. 12), degrees (0)\n"
    "  --grid DEG               lattice spacing, degrees (5)\n"
    "  --sample-draws N         random configurations the sampled fallback\n"
    "                           may draw where the lattice has no path\n"
    "                           (2000; 0: the lattice's answer alone)\n"
    "  --links L1,L2,L3         the arm's link lengths, metres\n"
    "                           (docs/spec.md section Arm: 0.09,0.332,0.538)\n"
    "  --link-radius M[,M2,M3]  the links' radii, metres: one for every\n"
    "                           link, or one each (0.02)\n"
    "  --tool-length-m M        a tool on link 3 beyond the end effector,\n"
    "                           collinear with it, checked like the links\n"
    "                           (docs/spec.md section Arm; 0: none)\n"
    "  --tool-radius-m M        the tool's capsule radius, metres (0; above\n"
    "                           0 only with a tool length)\n"
    "  --limits-deg a0,a1,s0,s1,e0,e1  the joint limits the plans keep\n"
    "                           to and the drives are held to (docs/spec.md\n"
    "                           section Arm: -180,180,-40,180,-180,140;\n"
    "                           alpha wraps only with -180,180)\n"
    "  --dijkstra               plain Dijkstra instead of A* (same cost)\n"
    "  --can IFACE              drive the arm on SocketCAN IFACE (off)\n"
    "  --can-nodes A,B,C        drive node ids of alpha, sigma, eta (1,2,3)\n"
    "  --counts-per-deg X[,Y,Z] drive counts per joint degree: one for\n"
    "                           every joint, or one each (1000)\n"
    "  --offset-counts A[,B,C]  each drive's counts at the joint's 0\n"
    "                           degrees (0)\n"
    "  --speed DEG_S[,S2,S3]    top joint speed (30)\n"
    "  --accel DEG_S2[,A2,A3]   joint acceleration (60); each one for\n"
    "                           every joint, or one each\n"
    "  --heartbeat-timeout MS   a drive silent this long is lost (300)\n"
    "  --sdo-timeout MS         one SDO attempt of three (50)\n"
    "  --consumer-heartbeat MS  each drive is told to quick-stop when it\n"
    "                           hears no heartbeat of ours this long (0x1016,\n"
    "                           0x6007; 300)\n"
    "  --keys DIR               take only LCM messages authenticated with a\n"
    "                           key whose NAME.key is in DIR (owner-only);\n"
    "                           without it, unsigned messages are taken, and\n"
    "                           --can refuses to start\n"
    "  --insecure-lcm           take unsigned messages even with --can\n"
    "                           (warned every minute): anyone who reaches\n"
    "                           the LCM port can then move the arm\n"
    "  --gen-key NAME           write a new key to DIR/NAME.key (a copy for\n"
    "                           the sender, a copy for --keys), then exit;\n"
    "                           with --role operator|sensor|joints\n"
    "                           (operator: plan requests; sensor: scans of\n"
    "                           sensor_id NAME; joints: joint states) and\n"
    "                           --key-dir DIR (.; made owner-only if new)\n"
    "  --log-level LEVEL        error, warn, info or debug (info)\n"
    "  --test-hooks             SIGUSR1 freezes the planner thread, SIGUSR2\n"
    "                           the guard thread (for the watchdog's tests)\n"
    "  --config FILE            read settings from FILE first\n"
    "  --help, --version\n"
    "SIGINT/SIGTERM: quick stop (with --can), then a clean exit.\n";

namespace
{

// "a,b,c": sensor ids as scans carry them (1..64 characters, no control
// characters; a comma separates). Appended to *ids, each once.
bool add_sensor_ids(const std::string &text, std::vector<std::string> *ids)
{
    std::vector<std::string> got;
    size_t from = 0;
    while (true) {
        size_t comma = text.find(',', from);
        std::string id =
            text.substr(from, comma == std::string::npos ? std::string::npos
                                                         : comma - from);
        if (id.empty() || id.size() > 64)
            return false;
        for (char c : id)
            if (static_cast<unsigned char>(c) < 0x20 || c == 0x7f)
                return false;
        got.push_back(id);
        if (comma == std::string::npos)
            break;
        from = comma + 1;
    }
    for (const std::string &id : got)
        if (std::find(ids->begin(), ids->end(), id) == ids->end())
            ids->push_back(id);
    return true;
}

bool channel_name_ok(const std::string &s)
{
    if (s.empty() || s.size() > 63) // LCM's longest channel name
        return false;
    for (char c : s)
        if (!std::isalnum(static_cast<unsigned char>(c)) && c != '_' &&
            c != '-' && c != '/' && c != ':')
            return false;
    return true;
}

// One setting; false with *error set if the key or value is bad.
bool apply(Options *o, const std::string &key, const std::string &value,
           std::string *error)
{
    double v = 0;
    auto bad = [&](const char *what) {
        *error = key + ": " + what + " (got '" + value + "')";
        return false;
    };
    auto number = [&](double lo, double hi) {
        return parse_numbers(value, &v, 1) && v >= lo && v <= hi;
    };
    std::string *channel = key == "scan-channel"      ? &o->scan_channel
                           : key == "cloud-channel"   ? &o->cloud_channel
                           : key == "request-channel" ? &o->request_channel
                           : key == "plan-channel"    ? &o->plan_channel
                           : key == "joint-channel"   ? &o->joint_channel
                           : key == "status-channel"  ? &o->status_channel
                                                      : nullptr;
    std::string wanted;
    if (is_drive_setting(key)) {
        if (!drive_setting(&o->can, key, value, &wanted))
            return bad(wanted.c_str());
    } else if (channel) {
        // LCM subscribes by regular expression: a '.' or '*' in a name
        // would take other channels' messages too
        if (!channel_name_ok(value))
            return bad("1..63 of A-Z a-z 0-9 _ - / :");
        *channel = value;
    } else if (key == "lcm-url")
        o->lcm_url = value;
    else if (key == "window") {
        if (!number(0, 3600))
            return bad("seconds in 0..3600");
        o->window_s = v;
    } else if (key == "mask") {
        if (value != "as-read" && value != "whole")
            return bad("as-read or whole");
        o->mask_as_read = value == "as-read";
    } else if (key == "mask-threads") {
        if (value != "1" && value != "2")
            return bad("1 or 2");
        o->mask_threads = value == "1" ? 1 : 2;
    } else if (key == "max-returns") {
        if (!number(1, 50000000) || v != std::floor(v))
            return bad("a count in 1..50000000");
        o->max_returns = long(v);
    } else if (key == "max-points") {
        if (!number(1000, 100000000) || v != std::floor(v))
            return bad("a count in 1000..100000000");
        o->max_points = long(v);
    } else if (key == "require-sensor" || key == "sensor") {
        if (!add_sensor_ids(value, key == "sensor" ? &o->other_sensors
                                                   : &o->required_sensors))
            return bad("sensor ids of 1..64 characters, comma-separated");
    } else if (key == "max-scan-age") {
        if (!number(0.01, 60))
            return bad("seconds in 0.01..60");
        o->max_scan_age_s = v;
    } else if (key == "max-clock-skew") {
        if (!number(0, 1))
            return bad("seconds in 0..1");
        o->max_clock_skew_s = v;
    } else if (key == "guard-deadline" || key == "planner-deadline") {
        if (!number(20, 60000))
            return bad("milliseconds in 20..60000");
        (key == "guard-deadline" ? o->guard_deadline_s
                                 : o->planner_deadline_s) = v * 1e-3;
    } else if (key == "test-hooks") {
        o->test_hooks = true;
    } else if (key == "margin") {
        if (!number(0, 1))
            return bad("metres in 0..1");
        o->params.margin_m = v;
    } else if (key == "cspace-margin") {
        if (!number(0, 20))
            return bad("degrees in 0..20");
        o->params.cspace_margin_deg = v;
    } else if (key == "sample-draws") {
        if (!number(0, QRT_SAMPLE_DRAWS_MAX) || v != std::floor(v))
            return bad("a count in 0..1000000");
        o->params.sample_draws = long(v);
    } else if (key == "grid") {
        if (!number(QRT_GRID_DEG_MIN, 20))
            return bad("degrees (a divisor of 20 at least the build's)");
        o->params.grid_deg = v;
    } else if (key == "link-radius") {
        double r[3];
        if (!parse_per_joint(value, r) || !all_within(r, 0.001, 0.5))
            return bad("metres in 0.001..0.5, one for every link or three");
        for (int j = 0; j < 3; j++)
            o->params.arm.link_radius_m[j] = r[j];
    } else if (key == "links") {
        double l[3];
        if (!parse_numbers(value, l, 3) || !all_within(l, 0.001, 10))
            return bad("three lengths L1,L2,L3 in metres, each in 0.001..10");
        for (int j = 0; j < 3; j++)
            o->params.arm.link_m[j] = l[j];
    } else if (key == "tool-length-m") {
        if (!number(0, 10))
            return bad("metres in 0..10 (0: no tool)");
        o->params.arm.tool_m = v;
    } else if (key == "tool-radius-m") {
        if (!number(0, 0.5))
            return bad("metres in 0..0.5");
        o->params.arm.tool_radius_m = v;
    } else if (key == "limits-deg") {
        if (!parse_limits_deg(value, o->params.arm.limit_deg))
            return bad(kLimitsDegWanted);
    } else if (key == "dijkstra") {
        o->params.use_astar = 0;
    } else if (key == "can") {
        o->can_iface = value;
    } else if (key == "can-nodes") {
        unsigned n[3];
        if (!qrt::parse_node_ids(value, n))
            return bad("three distinct node ids in 1..127, e.g. 1,2,3");
        for (int j = 0; j < 3; j++)
            o->can.node[j] = n[j];
    } else if (key == "heartbeat-timeout") {
        if (!number(20, 60000))
            return bad("milliseconds in 20..60000");
        o->can.heartbeat_timeout_us = uint32_t(v * 1000.0);
    } else if (key == "consumer-heartbeat") {
        if (!number(101, 65535) || v != std::floor(v))
            return bad("whole milliseconds in 101..65535, above the master's "
                       "100 ms heartbeat period");
        o->can.consumer_heartbeat_ms = uint16_t(v);
    } else if (key == "sdo-timeout") {
        if (!number(1, 10000))
            return bad("milliseconds in 1..10000");
        o->can.sdo_timeout_us = uint32_t(v * 1000.0);
    } else if (key == "keys") {
        o->keys_dir = value;
    } else if (key == "insecure-lcm") {
        o->insecure_lcm = true;
    } else if (key == "gen-key") {
        if (!key_name_ok(value))
            return bad("1..64 of A-Z a-z 0-9 _ - . (not starting with .)");
        o->gen_key_name = value;
    } else if (key == "role") {
        SenderRole role;
        if (!parse_role(value, &role))
            return bad("operator, sensor or joints");
        o->gen_key_role = value;
    } else if (key == "key-dir") {
        o->gen_key_dir = value;
    } else if (key == "log-level") {
        if (value != "error" && value != "warn" && value != "info" &&
            value != "debug")
            return bad("error, warn, info or debug");
        o->log_level = value;
    } else {
        *error = "unknown setting '" + key + "' (see --help)";
        return false;
    }
    return true;
}

bool takes_no_value(const std::string &key)
{
    return key == "dijkstra" || key == "test-hooks" || key == "insecure-lcm";
}

bool read_config(const std::string &path, Options *o, std::string *error)
{
    std::ifstream in(path);
    if (!in) {
        *error = path + ": cannot open: " + std::strerror(errno);
        return false;
    }
    std::string line;
    int lineno = 0;
    // a setting given twice is a mistake in one of the two lines; taking
    // the last would hide which one is in force
    std::map<std::string, int> set_on_line;
    while (std::getline(in, line)) {
        lineno++;
        if (lineno == 1 && line.compare(0, 3, "\xEF\xBB\xBF") == 0)
            line.erase(0, 3); // a UTF-8 byte-order mark, as some editors write
        auto hash = line.find('#');
        if (hash != std::string::npos)
            line.erase(hash);
        auto trim = [](std::string s) {
            size_t a = s.find_first_not_of(" \t\r"),
                   b = s.find_last_not_of(" \t\r");
            return a == std::string::npos ? std::string()
                                          : s.substr(a, b - a + 1);
        };
        line = trim(line);
        if (line.empty())
            continue;
        auto eq = line.find('=');
        std::string key = trim(line.substr(0, eq));
        std::string value =
            eq == std::string::npos ? "" : trim(line.substr(eq + 1));
        if (eq == std::string::npos && !takes_no_value(key)) {
            *error = path + ":" + std::to_string(lineno) + ": want key = value";
            return false;
        }
        auto [earlier, first_time] = set_on_line.emplace(key, lineno);
        if (!first_time) {
            *error = path + ":" + std::to_string(lineno) + ": " + key +
                     " is already set on line " +
                     std::to_string(earlier->second);
            return false;
        }
        if (!apply(o, key, value, error)) {
            *error = path + ":" + std::to_string(lineno) + ": " + *error;
            return false;
        }
    }
    if (in.bad()) { // a read error, or a directory (opens, cannot be read)
        *error = path + ": cannot read: " + std::strerror(errno);
        return false;
    }
    return true;
}

} // namespace

int parse_options(int argc, char **argv, Options *o, std::string *error)
{
    qrt_params_default(&o->params);
    qrtcan_master_config_default(&o->can);
    std::vector<std::string> args(argv + 1, argv + argc);
    // the config file first, so that flags override it
    for (size_t i = 0; i < args.size(); i++)
        if (args[i] == "--config") {
            if (i + 1 >= args.size()) {
                *error = "--config needs a file";
                return 2;
            }
            if (!read_config(args[i + 1], o, error))
                return 2;
        }
    for (size_t i = 0; i < args.size(); i++) {
        const std::string &a = args[i];
        if (a == "--help" || a == "-h") {
            std::fputs(kUsage, stdout);
            return 1;
        }
        if (a == "--version") {
            std::printf("qrtpland %s\n", QRTPLAN_VERSION);
            return 1;
        }
        if (a.compare(0, 2, "--") != 0) {
            *error = "unexpected argument '" + a + "' (see --help)";
            return 2;
        }
        std::string key = a.substr(2);
        if (key == "config") {
            i++;
            continue;
        }
        if (takes_no_value(key)) {
            if (!apply(o, key, "", error))
                return 2;
            continue;
        }
        if (i + 1 >= args.size()) {
            *error = a + " needs a value (see --help)";
            return 2;
        }
        if (!apply(o, key, args[++i], error))
            return 2;
    }
    // one way to say "no tool" (qrt_arm_validate): length 0, radius 0
    if (o->params.arm.tool_m == 0.0 && o->params.arm.tool_radius_m > 0.0) {
        *error = "--tool-radius-m needs --tool-length-m above 0 (a tool of "
                 "length 0 is no tool)";
        return 2;
    }
    // the drives are held to the joint limits the plans are made within
    for (int j = 0; j < 3; j++)
        for (int k = 0; k < 2; k++)
            o->can.limit_deg[j][k] = o->params.arm.limit_deg[j][k];
    return 0;
}

} // namespace qrt
