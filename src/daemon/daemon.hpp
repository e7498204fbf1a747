// The qrtplan daemon: LCM in and out, the planning core, and (with --can)
// the arm's drives.
//
// Three threads: LCM (decodes and validates messages, keeps only the newest
// scan per sensor and the newest request: a flood replaces, never queues),
// the planner (ingest, path check, mask, plan, publish), and the clock (the
// 1 Hz status and, with CAN, the joint state at 20 Hz). With CAN a fourth,
// the guard, checks the path the master is executing against every new
// scan with a planner of its own, so that a stop never waits for a replan
// to finish, and on a timer stops the arm when the evidence goes stale.
// With CAN the CAN link's thread watches the planner and the guard: either
// one silent past its deadline stops the arm and the master's heartbeat.
#pragma once

#include <array>
#include <atomic>
#include <condition_variable>
#include <cstdint>
#include <map>
#include <memory>
#include <mutex>
#include <set>
#include <string>
#include <vector>

#include <lcm/lcm-cpp.hpp>

#include "auth.hpp"
#include "can_link.hpp"
#include "ingest.hpp"
#include "options.hpp"
#include "qrtplan/plan_request_t.hpp"
#include "qrtplan/range_scan_t.hpp"

extern "C" {
#include "qrtplan/qrtplan.h"
}

namespace qrt
{

// What the signal handlers set: stop, and (with --test-hooks) freezing a
// thread so that the watchdog can be seen to work.
struct RunFlags {
    std::atomic<bool> stop{false};
    std::atomic<bool> freeze_planner{false};
    std::atomic<bool> freeze_guard{false};
};

class Daemon
{
  public:
    explicit Daemon(const Options &opts);
    ~Daemon();
    // Runs until flags.stop becomes true. Returns the exit status.
    int run(const RunFlags &flags);

  private:
    struct PendingScan {
        SensorMessage msg; // a scan or a cloud (ingest.hpp)
        int64_t received_us;
    };
    using Path = std::vector<std::array<double, 3>>;

    void on_scan(const lcm::ReceiveBuffer *rbuf, const std::string &channel);
    void on_cloud(const lcm::ReceiveBuffer *rbuf, const std::string &channel);
    void on_sensor(const lcm::ReceiveBuffer *rbuf, const std::string &channel,
                   SensorKind kind);
    void on_request(const lcm::ReceiveBuffer *rbuf, const std::string &channel);
    void on_joints(const lcm::ReceiveBuffer *rbuf, const std::string &channel);
    bool admit(const lcm::ReceiveBuffer *rbuf, const std::string &channel,
               SenderRole role, OpenedMessage *msg);
    bool sensor_taken(const std::string &id, std::string *why);
    void planner_loop(const RunFlags &flags);
    void clock_loop(const std::atomic<bool> &stop);
    void guard_loop(const RunFlags &flags);
    void guard_check(const CanLinkStatus &cs, int64_t received_us);
    void guard_evidence(const CanLinkStatus &cs);
    bool start_auth();
    bool host_alive(uint64_t now_us, std::string *why) const;
    Path rest_of_path(const CanLinkStatus &cs) const;
    bool executing_blocked(const CanLinkStatus &cs);
    bool same_goal(const qrtplan::plan_request_t &a,
                   const qrtplan::plan_request_t &b) const;
    void ingest(std::map<std::string, PendingScan> &scans, Picture *picture,
                bool report, long *invalid);
    Evidence evidence(const Picture &picture) const;
    void replan(std::map<std::string, PendingScan> &scans, bool new_request,
                int64_t trigger_us);
    void build_mask();
    void publish_plan(const qrt_plan *plan, const char *status,
                      const std::string &detail, bool blocked, int64_t ingest,
                      int64_t check, int64_t mask, int64_t search,
                      int64_t certify, int64_t trigger_us);
    bool current_joints(std::array<double, 3> *q);
    void reject(const std::string &why);
    static int64_t now_us();
    static int64_t wall_us();

    Options opts_;
    lcm::LCM lcm_;
    std::unique_ptr<CanLink> can_;
    std::unique_ptr<Authenticator> auth_; // LCM thread only, after run()
    std::unique_ptr<qrt_planner> planner_;
    Picture picture_;

    std::mutex mu_; // guards everything below
    std::condition_variable wake_;
    std::map<std::string, PendingScan> pending_scans_;
    // every sensor ever accepted: the picture keeps one entry per sensor, so
    // without a cap a stream of fresh sensor ids would grow it without
    // bound (with --require-sensor or --sensor, only those are taken)
    std::set<std::string> sensors_seen_;
    static constexpr size_t kMaxSensors = 32;
    // refused at intake, each counted once: stamped more than the allowed
    // skew ahead, older than the maximum age, from a sensor not taken
    int64_t scans_future_ = 0, scans_stale_ = 0, scans_unknown_sensor_ = 0;
    int64_t scans_over_budget_ = 0; // did not fit the picture's budget
    int64_t returns_out_of_reach_ = 0;
    int64_t evidence_stops_ = 0, watchdog_trips_ = 0;
    int64_t messages_authenticated_ = 0, messages_unsigned_ = 0;
    std::array<int64_t, kAuthRefusals> auth_refused_{}; // by AuthRefusal
    bool have_pending_request_ = false;
    qrtplan::plan_request_t pending_request_{};
    int64_t request_received_us_ = 0;
    bool have_joints_ = false;
    std::array<double, 3> joints_{};
    int64_t scans_received_ = 0, scans_dropped_ = 0, scans_rejected_ = 0;
    int64_t requests_received_ = 0, requests_rejected_ = 0;
    int64_t joint_states_rejected_ = 0;
    int64_t plans_published_ = 0, last_latency_us_ = 0;
    long picture_points_ = 0, points_dropped_ = 0;
    std::string last_error_;
    int64_t started_us_ = 0;
    // the guard's share (with CAN): its own queue of the newest scans
    std::condition_variable guard_wake_;
    // the guard is checking scans: the planner thread waits (briefly) so
    // that the stop does not share the CPU with a replan
    bool guard_busy_ = false;
    std::condition_variable guard_idle_;
    std::map<std::string, PendingScan> guard_scans_;
    // the guard stopped a blocked path that no plan has reported yet
    bool guard_stop_unreported_ = false;

    // the watchdog's view: when each guarding thread last went round its
    // loop (CanLink::now_us), read by the CAN link's thread
    std::atomic<uint64_t> planner_beat_us_{0}, guard_beat_us_{0};

    // guard thread only
    std::unique_ptr<qrt_planner> guard_planner_;
    Picture guard_picture_;
    std::vector<double> guard_gather_;

    // planner thread only
    bool have_goal_ = false;
    qrtplan::plan_request_t goal_{};
    // without CAN, the last ok plan (what an outside executor follows);
    // with CAN the master's own path is the one checked
    Path executing_;
    bool last_plan_ok_ = false; // so that going stale is published once
    std::vector<double> gather_;
    std::vector<double> gather_far_; // Picture::gather_far
    long returns_invalid_ = 0; // NaN/Inf or <= 0 ranges of the last ingest
};

} // namespace qrt
