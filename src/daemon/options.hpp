// qrtpland's settings: defaults, then a config file (--config), then flags.
#pragma once

#include <string>
#include <vector>

extern "C" {
#include "qrtcan/master.h"
#include "qrtplan/planner.h"
}

namespace qrt
{

struct Options {
    std::string lcm_url = "udpm://239.255.76.67:7667?ttl=0";
    std::string scan_channel = "QRT_SCAN";   // and QRT_SCAN_<sensor>...
    std::string cloud_channel = "QRT_CLOUD"; // and QRT_CLOUD_<sensor>...
    std::string request_channel = "QRT_PLAN_REQUEST";
    std::string plan_channel = "QRT_PLAN";
    std::string joint_channel = "QRT_JOINT_STATE";
    std::string status_channel = "QRT_STATUS";
    double window_s = 0.0;      // 0: the latest scan of each sensor
    bool mask_as_read = true;   // qrt_planner_plan_now, else the whole mask
    int mask_threads = 2;       // 1 or 2 (qrt_planner_build_mask_part)
    long max_returns = 1000000; // per scan; larger scans are rejected
    // the sensors whose fresh scans every plan and every motion needs; with
    // none, any one sensor's fresh scan will do
    std::vector<std::string> required_sensors;
    // further sensors taken but not required; with either list given, a
    // scan from a sensor on neither is refused
    std::vector<std::string> other_sensors;
    double max_scan_age_s = 0.5;     // older evidence is no evidence
    double max_clock_skew_s = 0.05;  // a scan stamped further ahead is refused
    long max_points = 2000000;       // in the obstacle picture, all sensors
    double guard_deadline_s = 0.2;   // the guard thread silent this long: stop
    double planner_deadline_s = 2.0; // the planner thread likewise
    bool test_hooks = false;         // SIGUSR1/SIGUSR2 freeze the planner/guard
    qrt_params params{};             // arm, margins, grid (qrt_params_default)
    std::string can_iface;           // empty: no CAN
    qrtcan_master_config can{};      // nodes, scales, speeds
    std::string log_level = "info";
    // who may change what the arm does (docs/security.md)
    std::string keys_dir;      // the trusted senders' NAME.key files
    bool insecure_lcm = false; // take unsigned messages (with --can too)
    // --gen-key NAME: write DIR/NAME.key, then exit
    std::string gen_key_name, gen_key_role = "operator", gen_key_dir = ".";
};

// Fills opts from argv (after defaults and any --config FILE). Returns 0 to
// run, 1 after printing --help/--version, 2 with *error set on bad input.
int parse_options(int argc, char **argv, Options *opts, std::string *error);

extern const char *kUsage;

} // namespace qrt
