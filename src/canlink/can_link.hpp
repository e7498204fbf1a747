// The daemon's CAN side: the CiA 402 master (include/qrtcan/master.h) run on
// its own thread over a SocketCAN raw socket.
//
// The thread polls the socket with a 1 ms timeout, hands every frame to the
// master, ticks it, and writes what it queued. Socket errors never end the
// thread: an interface that goes down (ENETDOWN), disappears (ENODEV), runs
// out of buffers (ENOBUFS) or reports bus-off (an error frame) is reported
// to the master as a bus error (the drives are then treated as lost, quick
// stop is sent as soon as the bus takes frames again) and the socket is
// reopened every half second until it works.
//
// Beside it, what qrtpland and qrtplan-exec both read from their options
// (node ids, numbers, per-joint values, the drive settings, the limits) and
// how both end --help: the one C++ home of each, as this library is the
// part both programs link.
#pragma once

#include <array>
#include <atomic>
#include <cstdint>
#include <functional>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

extern "C" {
#include "qrtcan/master.h"
}

namespace qrt
{

struct CanLinkStatus {
    qrtcan_master_status master{};
    std::string link; // "up", or why not ("down: Network is down", ...)
    unsigned long bus_errors = 0;
    unsigned long write_retries = 0; // ENOBUFS and the like
    unsigned long frames_written = 0;
    // taken from the master and never written: stale at a stop or a bus
    // error, or beyond the queue's room while the bus refused them
    unsigned long frames_unsent = 0;
    uint64_t last_quick_stop_us = 0; // CLOCK_MONOTONIC when written
    uint64_t last_heartbeat_us = 0;  // the master's own, likewise
    // the path the master is executing, waypoints in degrees: empty when
    // it has none (at rest, stopped, ramping down, faulted)
    std::vector<std::array<double, 3>> path;
    unsigned long host_watchdog_trips = 0; // times the host check said no
};

// "A,B,C": the drive node ids of alpha, sigma and eta, as the daemon's
// --can-nodes and qrtplan-exec's --nodes take them: three distinct ids in
// 1..127 (CANopen's range) and nothing else. False for anything more, less
// or wider, so that no id wraps into the range.
bool parse_node_ids(const std::string &text, unsigned ids[3]);

// "x,y,...": exactly n finite numbers, each field all number (no space,
// nothing empty). False, with out partly written, for anything else. The
// one number reader of qrtpland's and qrtplan-exec's options.
bool parse_numbers(const std::string &text, double *out, int n);

// "x" for all three joints (or links), or "x,y,z" one each: as the
// per-joint options of qrtpland and qrtplan-exec take them.
bool parse_per_joint(const std::string &text, double out[3]);

// After --help or --version: 0, or 2 with "program: stdout: write failed"
// on stderr when the text did not reach stdout (a script reading it must
// not get silence and success).
int finish_stdout(const char *program);

// Whether each of x[0..2] is in [lo, hi] (false for NaN).
bool all_within(const double x[3], double lo, double hi);

// The drive settings qrtpland and qrtplan-exec share, by option name without
// "--", each one value for every joint or three (parse_per_joint):
// counts-per-deg (1e-6..1e7 in size, the sign the drive's direction),
// offset-counts (each drive's counts at the joint's 0 degrees, whole,
// within 1e9), speed (deg/s) and accel (deg/s^2), both 0.001..10000.
// drive_setting takes one into cfg; false, with *wanted saying what the key
// takes, for a bad value.
bool is_drive_setting(const std::string &key);
bool drive_setting(qrtcan_master_config *cfg, const std::string &key,
                   const std::string &value, std::string *wanted);

// "a0,a1,s0,s1,e0,e1": the joint limits in degrees, as the daemon's
// --limits-deg and qrtplan-exec's take them: each low below its high, all
// within [-180, 180] (what the master takes). False for anything else, with
// lim untouched.
bool parse_limits_deg(const std::string &text, double lim[3][2]);
extern const char *const kLimitsDegWanted; // what the error says it takes

// The first waypoint outside cfg's joint limits (qrtcan_path_outside_limits,
// the test CanLink::set_path meets in the master), or -1 if none.
int path_outside_limits(const qrtcan_master_config &cfg,
                        const std::vector<std::array<double, 3>> &waypoints);

class CanLink
{
  public:
    CanLink(std::string iface, const qrtcan_master_config &cfg);
    ~CanLink(); // shutdown(), then the thread ends
    CanLink(const CanLink &) = delete;
    CanLink &operator=(const CanLink &) = delete;

    // Starts the thread and the drives' bring-up. False (with why) only for
    // a configuration the master refuses; a missing interface is retried.
    bool start(std::string *why);

    // A path from where the arm stands (see qrtcan_master_set_path).
    // Returns QRTCAN_OK or the master's refusal.
    int set_path(const std::vector<std::array<double, 3>> &waypoints);

    // Stop now; the quick-stop frames are written before this returns
    // (unless the bus is down).
    void quick_stop();

    // Quick stop to every drive, held there for good: the master takes no
    // more paths and sends no more heartbeat (qrtcan_master_shutdown), so
    // the drives' consumers keep them stopped if this process then hangs.
    // What a stopping process does first, before it waits for its other
    // threads; the link's thread runs on until the destructor, which sends
    // the stops once more.
    void shutdown();

    CanLinkStatus status() const;

    // Asked on the link's thread every cycle (about 1 ms) with now_us():
    // whether the host's threads that guard motion are alive, and if not,
    // why. While it answers no, the master holds the arm stopped and sends
    // no heartbeat (qrtcan_master_set_host_alive), so the drives' heartbeat
    // consumers stop them even if this process then hangs. nullptr: none.
    using HostCheck = std::function<bool(uint64_t now_us, std::string *why)>;
    void set_host_check(HostCheck check);

    static uint64_t now_us();

  private:
    void run();
    void open_socket(uint64_t now);
    void close_socket();
    void flush(uint64_t now); // call with mu_ held
    void bus_error(uint64_t now, const std::string &why);
    void discard_pending(size_t n); // the oldest n, counted
    // call with mu_ held; what to log (after the lock), "" if nothing new
    std::string check_host(uint64_t now);

    std::string iface_;
    qrtcan_master_config cfg_;
    mutable std::mutex mu_;
    qrtcan_master master_{};
    int fd_ = -1;
    std::string link_ = "not started";
    uint64_t next_open_us_ = 0;
    unsigned long bus_errors_ = 0, write_retries_ = 0;
    unsigned long frames_written_ = 0, frames_unsent_ = 0;
    uint64_t last_quick_stop_us_ = 0, last_heartbeat_us_ = 0;
    HostCheck host_check_;
    bool host_alive_ = true;
    unsigned long host_watchdog_trips_ = 0;
    uint64_t nobuf_since_ = 0;          // first ENOBUFS of the present run
    std::vector<qrtcan_frame> pending_; // taken from the master, not written
    std::atomic<bool> stop_{false};
    std::thread thread_;
};

} // namespace qrt
