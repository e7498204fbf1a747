#include "daemon.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstring>
#include <pthread.h>
#include <sched.h>
#include <sodium.h>
#include <thread>

#include "decode.hpp"
#include "end_check.h"
#include "lcm_loss.hpp"
#include "log.hpp"
#include "qrtplan/daemon_status_t.hpp"
#include "qrtplan/joint_state_t.hpp"
#include "qrtplan/joints.h"
#include "qrtplan/plan_t.hpp"

namespace qrt
{

namespace
{

// Largest joint difference, alpha the short way.
double joint_gap(const double a[3], const double b[3])
{
    double g = std::fabs(qrt_wrap_deg(a[0] - b[0]));
    for (int j = 1; j < 3; j++)
        g = std::max(g, std::fabs(a[j] - b[j]));
    return g;
}

} // namespace

int64_t Daemon::now_us()
{
    return std::chrono::duration_cast<std::chrono::microseconds>(
               std::chrono::steady_clock::now().time_since_epoch())
        .count();
}

int64_t Daemon::wall_us()
{
    return std::chrono::duration_cast<std::chrono::microseconds>(
               std::chrono::system_clock::now().time_since_epoch())
        .count();
}

// A planner's 4 MiB touched now, so that the first replan or stop does not
// pay for the page faults.
static qrt_planner *new_planner()
{
    auto *p = new qrt_planner;
    std::memset(static_cast<void *>(p), 0, sizeof *p);
    return p;
}

Daemon::Daemon(const Options &opts)
    : opts_(opts), lcm_(opts.lcm_url), planner_(new_planner()),
      picture_(opts.window_s, opts.max_points),
      guard_picture_(opts.window_s, opts.max_points)
{
}

Daemon::~Daemon() = default;

void Daemon::reject(const std::string &why)
{
    last_error_ = why; // caller holds mu_
    log_limited(LogLevel::warn, "%s", why.c_str());
}

// --- the LCM thread --------------------------------------------------------

// The message a handler may act on (auth.hpp), or false after counting and
// logging the refusal.
bool Daemon::admit(const lcm::ReceiveBuffer *rbuf, const std::string &channel,
                   SenderRole role, OpenedMessage *msg)
{
    AuthRefusal reason{};
    std::string why;
    bool ok = auth_->open(channel, static_cast<const uint8_t *>(rbuf->data),
                          size_t(rbuf->data_size), role, wall_us(), msg,
                          &reason, &why);
    std::lock_guard<std::mutex> lock(mu_);
    if (!ok) {
        auth_refused_[size_t(reason)]++;
        reject(channel + ": refused (" + refusal_name(reason) + "): " + why);
    } else
        (msg->sender ? messages_authenticated_ : messages_unsigned_)++;
    return ok;
}

// Caller holds mu_. With --require-sensor or --sensor only those ids are
// taken; without, the first kMaxSensors ids seen.
bool Daemon::sensor_taken(const std::string &id, std::string *why)
{
    const auto &req = opts_.required_sensors, &other = opts_.other_sensors;
    if (!req.empty() || !other.empty()) {
        if (std::find(req.begin(), req.end(), id) != req.end() ||
            std::find(other.begin(), other.end(), id) != other.end())
            return true;
        *why = "sensor '" + id + "' is not one of --require-sensor/--sensor";
        return false;
    }
    if (sensors_seen_.count(id) != 0)
        return true;
    if (sensors_seen_.size() >= kMaxSensors) {
        *why = "sensor '" + id + "' beyond the " + std::to_string(kMaxSensors) +
               " sensors already seen";
        return false;
    }
    sensors_seen_.insert(id);
    return true;
}

void Daemon::on_scan(const lcm::ReceiveBuffer *rbuf, const std::string &channel)
{
    on_sensor(rbuf, channel, SensorKind::scan);
}

void Daemon::on_cloud(const lcm::ReceiveBuffer *rbuf,
                      const std::string &channel)
{
    on_sensor(rbuf, channel, SensorKind::cloud);
}

// A range scan or a point cloud: the same rules for both, counted in the
// same scans_* counters (docs/spec-interfaces.md).
void Daemon::on_sensor(const lcm::ReceiveBuffer *rbuf,
                       const std::string &channel, SensorKind kind)
{
    int64_t t = now_us(), wall = wall_us();
    const char *what = kind == SensorKind::scan ? "scan" : "cloud";
    PendingScan p;
    p.received_us = t;
    OpenedMessage in;
    if (!admit(rbuf, channel, SenderRole::sensor, &in))
        return;
    // refused here, a bad message never displaces a good pending one
    std::string why = decode_sensor_message(in.payload, in.payload_size, kind,
                                            opts_.max_returns, &p.msg);
    std::lock_guard<std::mutex> lock(mu_);
    if (!why.empty()) {
        scans_rejected_++;
        reject(channel + ": " + what + " refused: " + why);
        return;
    }
    const std::string &id = p.msg.sensor_id();
    // a sensor's key speaks for that sensor only: another's scans from it
    // could erase the other sensor's obstacles
    if (in.sender && in.sender->name != id) {
        auth_refused_[size_t(AuthRefusal::not_permitted)]++;
        reject(channel + ": " + what + " refused: sensor key '" +
               in.sender->name + "' sent a " + what + " of sensor '" + id +
               "'");
        return;
    }
    if (!sensor_taken(id, &why)) {
        scans_unknown_sensor_++;
        reject(channel + ": " + what + " refused: " + why);
        return;
    }
    // the stamp against this computer's clock (docs: both keep
    // CLOCK_REALTIME within the skew): a scan from the future would outlive
    // every fresh one, a scan older than the maximum age is no evidence
    const int64_t skew = int64_t(opts_.max_clock_skew_s * 1e6);
    const int64_t max_age = int64_t(opts_.max_scan_age_s * 1e6);
    const int64_t utime = p.msg.utime();
    if (utime > wall + skew) {
        scans_future_++;
        reject(channel + ": " + what + " from '" + id + "' refused: stamped " +
               std::to_string((utime - wall) / 1000) +
               " ms ahead of this computer's clock");
        return;
    }
    if (wall - utime > max_age) {
        scans_stale_++;
        reject(channel + ": " + what + " from '" + id +
               "' refused: " + std::to_string((wall - utime) / 1000) +
               " ms old, over --max-scan-age");
        return;
    }
    scans_received_++;
    if (guard_planner_) { // latest wins here too (not counted twice)
        guard_scans_[id] = p;
        guard_wake_.notify_one();
    }
    auto it = pending_scans_.find(id);
    if (it != pending_scans_.end()) {
        scans_dropped_++; // latest wins: the older one was never used
        it->second = std::move(p);
    } else {
        pending_scans_.emplace(id, std::move(p));
    }
    wake_.notify_one();
}

void Daemon::on_request(const lcm::ReceiveBuffer *rbuf,
                        const std::string &channel)
{
    OpenedMessage in;
    if (!admit(rbuf, channel, SenderRole::operator_, &in))
        return;
    qrtplan::plan_request_t r;
    int rc = safe_decode(&r, in.payload, in.payload_size);
    std::lock_guard<std::mutex> lock(mu_);
    if (rc < 0) {
        requests_rejected_++;
        reject(channel +
               ": not a qrtplan.plan_request_t (wrong type "
               "fingerprint or truncated, " +
               std::to_string(in.payload_size) + " bytes)");
        return;
    }
    requests_received_++;
    pending_request_ = r;
    have_pending_request_ = true;
    request_received_us_ = now_us();
    wake_.notify_one();
}

void Daemon::on_joints(const lcm::ReceiveBuffer *rbuf,
                       const std::string &channel)
{
    OpenedMessage in;
    if (!admit(rbuf, channel, SenderRole::joints, &in))
        return;
    qrtplan::joint_state_t js;
    // fingerprint 8, utime 8, joints 24, moving 1, then drive_state
    int rc = lcm_string_ok(in.payload, in.payload_size, 41)
                 ? safe_decode(&js, in.payload, in.payload_size)
                 : -1;
    std::lock_guard<std::mutex> lock(mu_);
    if (rc < 0 || !std::isfinite(js.joints_deg[0]) ||
        !std::isfinite(js.joints_deg[1]) || !std::isfinite(js.joints_deg[2])) {
        joint_states_rejected_++;
        reject(channel + ": joint state refused (wrong type, truncated or "
                         "non-finite)");
        return;
    }
    for (int j = 0; j < 3; j++)
        joints_[size_t(j)] = js.joints_deg[j];
    have_joints_ = true;
}

// --- the planner thread ----------------------------------------------------

bool Daemon::current_joints(std::array<double, 3> *q)
{
    if (can_) {
        CanLinkStatus st = can_->status();
        if (!st.master.all_positions_known)
            return false;
        for (int j = 0; j < 3; j++)
            (*q)[size_t(j)] = st.master.joints_deg[j];
        return true;
    }
    std::lock_guard<std::mutex> lock(mu_);
    *q = joints_;
    return have_joints_;
}

void Daemon::build_mask()
{
    qrt_planner *pl = planner_.get();
    if (opts_.mask_threads < 2) {
        qrt_planner_build_mask(pl);
        return;
    }
    qrt_planner_build_mask_begin(pl);
    std::thread other([pl] { qrt_planner_build_mask_part(pl, 1, 2); });
    qrt_planner_build_mask_part(pl, 0, 2);
    other.join();
    qrt_planner_build_mask_end(pl);
}

void Daemon::publish_plan(const qrt_plan *plan, const char *status,
                          const std::string &detail, bool blocked,
                          int64_t ingest, int64_t check, int64_t mask,
                          int64_t search, int64_t certify, int64_t trigger_us)
{
    qrtplan::plan_t out{};
    out.request_id = goal_.request_id;
    out.scan_utime = picture_.newest_utime();
    out.status = status;
    out.detail = detail;
    out.executing_path_blocked = blocked;
    out.ingest_us = ingest;
    out.check_us = check;
    out.mask_us = mask;
    out.search_us = search;
    out.certify_us = certify;
    out.cells_blocked = -1; // no plan: no mask built for it
    if (plan) {
        out.n_waypoints = plan->status == QRT_STATUS_OK ? plan->n_waypoints : 0;
        for (int i = 0; i < out.n_waypoints; i++)
            out.waypoints_deg.push_back({plan->waypoints_deg[i][0],
                                         plan->waypoints_deg[i][1],
                                         plan->waypoints_deg[i][2]});
        out.cost_deg = plan->cost_deg;
        out.clearance_m =
            plan->status == QRT_STATUS_OK ? plan->clearance_m : 0.0;
        out.cells_blocked = int32_t(plan->cells_blocked);
        for (int j = 0; j < 3; j++) {
            out.start_deg[j] = plan->start_deg[j];
            out.goal_deg[j] = plan->goal_deg[j];
        }
        // QRT_FACING_* and QRT_ELBOW_* are plan_t's numbers; 0 unless the
        // goal was a point and the plan gives its joints
        out.goal_ik_facing = int8_t(plan->goal_ik.facing);
        out.goal_ik_elbow = int8_t(plan->goal_ik.elbow);
        out.points = int32_t(plan->points);
        out.points_dropped = int32_t(plan->points_dropped);
        out.voxel_m = plan->voxel_m;
    }
    out.returns_invalid = int32_t(returns_invalid_);
    out.utime = wall_us();
    out.total_us = now_us() - trigger_us;
    lcm_.publish(opts_.plan_channel, &out);
    std::lock_guard<std::mutex> lock(mu_);
    plans_published_++;
    last_latency_us_ = out.total_us;
    points_dropped_ = out.points_dropped;
}

// Scans into a picture (the planner's, which reports refusals, invalid
// returns and the budget, or the guard's, which leaves that to the
// planner).
void Daemon::ingest(std::map<std::string, PendingScan> &scans, Picture *picture,
                    bool report, long *invalid)
{
    const qrt_arm &arm = opts_.params.arm;
    const double reach = arm_reach_m(arm, opts_.params.margin_m);
    for (auto &kv : scans) {
        ScanPoints sp;
        const SensorMessage &m = kv.second.msg;
        std::string why = to_points(m, opts_.max_returns, reach, &sp);
        if (!why.empty()) {
            if (report) {
                std::lock_guard<std::mutex> lock(mu_);
                scans_rejected_++;
                reject(std::string(m.kind()) + " from '" + kv.first +
                       "' refused: " + why);
            }
            continue;
        }
        *invalid += sp.invalid;
        long far = sp.out_of_reach, n = long(sp.xyz.size() / 3);
        if (sp.invalid > 0 && report)
            log(LogLevel::debug, "%s from '%s': %ld returns NaN/Inf or <= 0",
                m.kind(), kv.first.c_str(), sp.invalid);
        bool fits = picture->add(std::move(sp), wall_us());
        if (!report)
            continue;
        std::lock_guard<std::mutex> lock(mu_);
        returns_out_of_reach_ += far;
        if (!fits) {
            scans_over_budget_++;
            reject(std::string(m.kind()) + " from '" + kv.first +
                   "' refused: its " + std::to_string(n) +
                   " points in reach do not fit the obstacle picture's "
                   "--max-points " +
                   std::to_string(opts_.max_points) +
                   " beside the other sensors' newest scans");
        }
    }
}

Evidence Daemon::evidence(const Picture &picture) const
{
    return picture.evidence(wall_us(), opts_.required_sensors,
                            int64_t(opts_.max_scan_age_s * 1e6));
}

// The rest of the path the master is executing: from where the drives are
// to the waypoint being approached, then the waypoints after it. Empty
// when the master has no path (at rest, stopped, or ramping down).
Daemon::Path Daemon::rest_of_path(const CanLinkStatus &cs) const
{
    Path rest;
    if (cs.path.size() < 2 || !cs.master.all_positions_known)
        return rest;
    rest.push_back({cs.master.joints_deg[0], cs.master.joints_deg[1],
                    cs.master.joints_deg[2]});
    for (size_t i = size_t(std::max(cs.master.waypoint, 1)); i < cs.path.size();
         i++)
        rest.push_back(cs.path[i]);
    return rest;
}

// The path being executed still free among the points now in the planner?
// With CAN that is the master's path (rest_of_path), else the last ok
// plan. Asked after the plan, on the rows it built (the guard thread, with
// CAN, asks first on its own); a blocked path is dropped and the arm
// stopped.
bool Daemon::executing_blocked(const CanLinkStatus &cs)
{
    Path rest = can_ ? rest_of_path(cs) : executing_;
    if (rest.size() < 2)
        return false;
    int first = -1;
    const double(*wp)[3] = reinterpret_cast<const double(*)[3]>(rest.data());
    // a whole mask is built: ask it; else build the path's rows (most of
    // them the plan has just built)
    int rc = opts_.mask_as_read
                 ? qrt_planner_check_path_now(planner_.get(), wp,
                                              int(rest.size()), &first)
                 : qrt_planner_check_path(planner_.get(), wp, int(rest.size()),
                                          &first);
    if (rc != QRT_OK || first < 0)
        return false;
    if (can_) {
        // the guard may have stopped it already: a second stop is harmless
        can_->quick_stop();
        log(LogLevel::warn,
            "the path being executed is blocked (segment %d): quick stop sent",
            first);
    } else {
        log(LogLevel::warn, "the path being executed is blocked (segment %d)",
            first);
        executing_.clear();
    }
    return true;
}

bool Daemon::same_goal(const qrtplan::plan_request_t &a,
                       const qrtplan::plan_request_t &b) const
{
    if (a.goal_kind != b.goal_kind || a.has_start != b.has_start)
        return false;
    if (a.goal_kind == qrtplan::plan_request_t::GOAL_XYZ &&
        (a.ik_facing != b.ik_facing || a.ik_elbow != b.ik_elbow))
        return false;
    for (int j = 0; j < 3; j++)
        if (a.goal[j] != b.goal[j] ||
            (a.has_start && a.start_deg[j] != b.start_deg[j]))
            return false;
    return true;
}

void Daemon::replan(std::map<std::string, PendingScan> &scans, bool new_request,
                    int64_t trigger_us)
{
    qrt_planner *pl = planner_.get();
    int64_t t0 = now_us();
    long invalid = 0;
    ingest(scans, &picture_, true, &invalid);
    int64_t t1 = now_us();
    returns_invalid_ = invalid;
    picture_.gather(&gather_);
    {
        std::lock_guard<std::mutex> lock(mu_);
        picture_points_ = long(gather_.size() / 3);
    }
    planner_beat_us_ = CanLink::now_us();
    if (!have_goal_)
        return; // the picture is kept up to date; nothing to plan for
    qrt_planner_clear_points(pl);
    // first the nearest point beyond reach of each sensor: the core ignores
    // them as out of reach (not in the table, not in plan_t.points) but
    // keeps their least distance from the base, which its clearance
    // certificate counts for every point ingest dropped. A call of their
    // own, so that a picture filling the exact table stays exact.
    picture_.gather_far(&gather_far_);
    qrt_planner_add_points(pl, gather_far_.data(),
                           long(gather_far_.size() / 3));
    qrt_planner_add_points(pl, gather_.data(), long(gather_.size() / 3));

    std::array<double, 3> here{};
    bool know_here = current_joints(&here);
    CanLinkStatus cs;
    if (can_)
        cs = can_->status();
    Evidence ev = evidence(picture_);
    if (!ev.fresh()) {
        // no plan on missing or stale evidence; a path being executed on
        // it is stopped (the guard does so too, on its timer)
        if (can_ && !cs.path.empty()) {
            can_->quick_stop();
            {
                std::lock_guard<std::mutex> lock(mu_);
                evidence_stops_++;
            }
            log(LogLevel::warn, "%s: quick stop sent", ev.detail.c_str());
        }
        executing_.clear();
        last_plan_ok_ = false;
        publish_plan(nullptr, ev.status.c_str(), ev.detail, false, t1 - t0, 0,
                     0, 0, 0, trigger_us);
        return;
    }
    int64_t t_mask = now_us();
    if (!opts_.mask_as_read)
        build_mask();
    int64_t t2 = now_us();
    planner_beat_us_ = CanLink::now_us();

    qrt_target start{}, goal{};
    goal.kind = goal_.goal_kind == qrtplan::plan_request_t::GOAL_XYZ
                    ? QRT_TARGET_XYZ
                    : QRT_TARGET_JOINTS;
    for (int j = 0; j < 3; j++)
        goal.value[j] = goal_.goal[j];
    // the constants of plan_request_t are the core's enum values (checked
    // when the request came in)
    goal.ik.facing = static_cast<qrt_ik_facing>(goal_.ik_facing);
    goal.ik.elbow = static_cast<qrt_ik_elbow>(goal_.ik_elbow);
    start.kind = QRT_TARGET_JOINTS;
    if (goal_.has_start && (new_request || !know_here)) {
        for (int j = 0; j < 3; j++)
            start.value[j] = goal_.start_deg[j];
    } else if (know_here) {
        for (int j = 0; j < 3; j++)
            start.value[j] = here[size_t(j)];
    } else {
        int64_t tc = now_us();
        bool blocked = executing_blocked(cs);
        last_plan_ok_ = false;
        publish_plan(nullptr, "invalid_request",
                     "no start: the request has none and no joint state has "
                     "been received on " +
                         opts_.joint_channel,
                     blocked, t1 - t0, now_us() - tc, t2 - t_mask, 0, 0,
                     trigger_us);
        return;
    }
    static qrt_plan plan; // 6 KiB: not on the thread's stack
    int rc = opts_.mask_as_read ? qrt_planner_plan_now(pl, &start, &goal, &plan)
                                : qrt_planner_plan(pl, &start, &goal, &plan);
    int64_t t3 = now_us();
    planner_beat_us_ = CanLink::now_us();
    // as read, mask and search are one stage: all of it counts as the mask
    int64_t mask_us = opts_.mask_as_read ? t3 - t2 : t2 - t_mask;
    int64_t search_us = opts_.mask_as_read ? 0 : t3 - t2;
    // the path being executed, on the rows the plan has just built (and
    // the few more it passes through)
    if (can_)
        cs = can_->status();
    bool blocked = executing_blocked(cs);
    {
        // the guard saw it first (the planner waits for it with each scan)
        // and stopped the arm: the master has no path left to check, but
        // this plan is the one to say that the path was blocked
        std::lock_guard<std::mutex> lock(mu_);
        blocked = blocked || guard_stop_unreported_;
        guard_stop_unreported_ = false;
    }
    int64_t check_us = now_us() - t3;
    if (rc != QRT_OK) {
        std::string why = std::string("the request is invalid: ") +
                          qrt_err_name(rc) +
                          (rc == QRT_E_LIMITS ? " (joints outside the limits)"
                                              : " (NaN/Inf or a bad goal)");
        {
            std::lock_guard<std::mutex> lock(mu_);
            reject(why);
        }
        last_plan_ok_ = false;
        publish_plan(nullptr, "invalid_request", why, blocked, t1 - t0,
                     check_us, mask_us, search_us, 0, trigger_us);
        return;
    }
    // a blocked end the core left unmeasured (merged points) is measured
    // against the picture's exact points: "collides" only if they collide
    char detail[END_CHECK_DETAIL_LEN];
    if (end_check_needed(&plan)) {
        end_check c;
        end_check_begin(&c, pl, &opts_.params.arm, &plan, &start, &goal);
        end_check_add(&c, gather_.data(), long(gather_.size() / 3));
        plan.end_measured = 1;
        plan.end_clearance_m = end_check_clearance(&c);
    }
    if (end_check_measured(&plan)) {
        end_check_detail(
            &plan, plan.status == QRT_STATUS_GOAL_BLOCKED ? &goal : &start,
            &opts_.params, detail, sizeof detail);
        plan.detail = detail;
    }
    // an ok plan's clearance, certified against the table it was made on
    // (the far points included): a stage of its own, as it can cost more
    // than a small plan (a pass over the points for every sample)
    int64_t certify_us = 0;
    if (plan.status == QRT_STATUS_OK) {
        int64_t tc = now_us();
        qrt_planner_certify_clearance(pl, &plan);
        certify_us = now_us() - tc;
        planner_beat_us_ = CanLink::now_us();
    }
    last_plan_ok_ = plan.status == QRT_STATUS_OK;
    publish_plan(&plan, qrt_plan_status_name(plan.status),
                 plan.detail ? plan.detail : "", blocked, t1 - t0, check_us,
                 mask_us, search_us, certify_us, trigger_us);
    if (plan.status != QRT_STATUS_OK)
        return;
    Path path;
    for (int i = 0; i < plan.n_waypoints; i++)
        path.push_back({plan.waypoints_deg[i][0], plan.waypoints_deg[i][1],
                        plan.waypoints_deg[i][2]});
    if (!can_) {
        executing_ = path;
        return;
    }
    // the drives take a new path only at rest; a free path being executed
    // goes on (it was just checked)
    cs = can_->status();
    bool at_rest = cs.master.state == QRTCAN_MASTER_READY ||
                   cs.master.state == QRTCAN_MASTER_STOPPED;
    if (at_rest && path.size() >= 2 &&
        joint_gap(path.front().data(), path.back().data()) > 0.01) {
        // the evidence once more, as late as can be: the plan took time
        Evidence late = evidence(picture_);
        if (!late.fresh()) {
            log(LogLevel::warn, "path not handed to the drives: %s",
                late.detail.c_str());
            return;
        }
        int r = can_->set_path(path);
        if (r == QRTCAN_OK)
            log(LogLevel::info, "executing a path of %zu waypoints",
                path.size());
        else if (r == QRTCAN_E_CMD) // not at rest yet: the next plan will do
            log(LogLevel::debug, "drives did not take the path yet: %s",
                qrtcan_strerror(r));
        else // a plan the drives cannot execute must not look like motion
            log_limited(LogLevel::warn,
                        "the master refused the path (%s): the arm does not "
                        "move",
                        qrtcan_strerror(r));
    }
}

// Longest a replan waits for the guard thread to check the same scan.
constexpr int GUARD_YIELD_MS = 40;
// How often the planner thread wakes without a scan (the resume and the
// evidence's timer) and the guard thread likewise (the evidence's timer).
constexpr int PLANNER_TICK_MS = 50;
constexpr int GUARD_TICK_MS = 10;

void Daemon::planner_loop(const RunFlags &flags)
{
    const std::atomic<bool> &stop = flags.stop;
    while (!stop) {
        planner_beat_us_ = CanLink::now_us();
        while (flags.freeze_planner && !stop) // --test-hooks: a stalled thread
            std::this_thread::sleep_for(std::chrono::milliseconds(10));
        std::map<std::string, PendingScan> scans;
        bool new_request = false;
        int64_t trigger = 0;
        qrtplan::plan_request_t previous_goal = goal_;
        bool had_goal = have_goal_;
        {
            std::unique_lock<std::mutex> lock(mu_);
            wake_.wait_for(lock, std::chrono::milliseconds(PLANNER_TICK_MS),
                           [&] {
                               return stop || !pending_scans_.empty() ||
                                      have_pending_request_;
                           });
            scans.swap(pending_scans_);
            // a scan that may stop the arm goes to the guard first: the
            // replan starts when the guard is done with it (or after
            // GUARD_YIELD_MS, so a slow guard cannot hold plans back)
            if (guard_planner_ && !scans.empty())
                guard_idle_.wait_for(
                    lock, std::chrono::milliseconds(GUARD_YIELD_MS), [&] {
                        return stop || (!guard_busy_ && guard_scans_.empty());
                    });
            if (have_pending_request_) {
                have_pending_request_ = false;
                new_request = true;
                goal_ = pending_request_;
                trigger = request_received_us_;
            }
        }
        planner_beat_us_ = CanLink::now_us();
        for (auto &kv : scans)
            trigger = std::max(trigger, kv.second.received_us);
        if (new_request) {
            bool finite = true;
            for (int j = 0; j < 3; j++)
                finite =
                    finite && std::isfinite(goal_.goal[j]) &&
                    (!goal_.has_start || std::isfinite(goal_.start_deg[j]));
            bool xyz = goal_.goal_kind == qrtplan::plan_request_t::GOAL_XYZ;
            qrt_ik_branch ik{};
            ik.facing = static_cast<qrt_ik_facing>(goal_.ik_facing);
            ik.elbow = static_cast<qrt_ik_elbow>(goal_.ik_elbow);
            bool valid = finite &&
                         (xyz || goal_.goal_kind ==
                                     qrtplan::plan_request_t::GOAL_JOINTS) &&
                         (!xyz || qrt_ik_branch_check(&ik) == QRT_OK);
            // a new goal while the drives execute a path: stop, and the new
            // path starts from rest (the master takes paths only at rest,
            // and the old path leads where the operator no longer wants
            // the arm); a request repeating the goal changes nothing
            if (can_ &&
                (!valid || !had_goal || !same_goal(goal_, previous_goal)) &&
                !can_->status().path.empty()) {
                can_->quick_stop();
                log(LogLevel::info,
                    "new goal (request %lld) while moving: "
                    "quick stop, the new path starts from rest",
                    static_cast<long long>(goal_.request_id));
            }
            if (!valid) {
                {
                    std::lock_guard<std::mutex> lock(mu_);
                    requests_rejected_++;
                    reject("plan request " + std::to_string(goal_.request_id) +
                           " refused: NaN/Inf, an unknown goal kind or an "
                           "unknown IK branch");
                }
                publish_plan(nullptr, "invalid_request",
                             "NaN/Inf values, an unknown goal kind or an "
                             "unknown IK branch (ik_facing and ik_elbow are "
                             "0, 1 or 2)",
                             false, 0, 0, 0, 0, 0, trigger);
                have_goal_ = false;
                last_plan_ok_ = false;
                continue;
            }
            have_goal_ = true;
        }
        // the evidence went stale since the last ok plan: say so once (an
        // outside executor must stop; with CAN the guard stops the arm)
        if (have_goal_ && last_plan_ok_ && scans.empty() && !new_request) {
            Evidence ev = evidence(picture_);
            if (!ev.fresh()) {
                last_plan_ok_ = false;
                executing_.clear();
                publish_plan(nullptr, ev.status.c_str(), ev.detail, false, 0, 0,
                             0, 0, 0, now_us());
                continue;
            }
        }
        // with the drives idle short of the goal, plan again without a scan
        bool resume = false;
        if (can_ && have_goal_ && scans.empty() && !new_request) {
            CanLinkStatus cs = can_->status();
            std::array<double, 3> here{};
            if (cs.master.state == QRTCAN_MASTER_READY &&
                current_joints(&here) &&
                goal_.goal_kind == qrtplan::plan_request_t::GOAL_JOINTS &&
                joint_gap(here.data(), goal_.goal) > 0.5 && cs.path.empty() &&
                evidence(picture_).fresh()) {
                resume = true;
                trigger = now_us();
            }
        }
        if (scans.empty() && !new_request && !resume)
            continue;
        replan(scans, new_request || resume, trigger);
    }
}

// --- the guard thread (with CAN) -------------------------------------------

// The evidence on the guard's timer: the master executing a path while a
// required sensor has gone quiet (or every sensor, with none required) is
// stopped within GUARD_TICK_MS of the scan's age passing the maximum.
void Daemon::guard_evidence(const CanLinkStatus &cs)
{
    if (cs.path.empty())
        return;
    Evidence ev = evidence(guard_picture_);
    if (ev.fresh())
        return;
    can_->quick_stop();
    {
        std::lock_guard<std::mutex> lock(mu_);
        evidence_stops_++;
    }
    log(LogLevel::warn, "%s: quick stop sent", ev.detail.c_str());
}

// The path the master is executing against the guard's picture, with only
// its own rows of the mask (qrt_planner_check_path_now): a quick stop the
// moment a scan blocks it, whatever the planner thread is doing.
void Daemon::guard_check(const CanLinkStatus &cs, int64_t received)
{
    int64_t t1 = now_us();
    Path rest = rest_of_path(cs);
    if (rest.size() < 2)
        return;
    qrt_planner *pl = guard_planner_.get();
    guard_picture_.gather(&guard_gather_);
    qrt_planner_clear_points(pl);
    qrt_planner_add_points(pl, guard_gather_.data(),
                           long(guard_gather_.size() / 3));
    int first = -1;
    if (qrt_planner_check_path_now(
            pl, reinterpret_cast<const double(*)[3]>(rest.data()),
            int(rest.size()), &first) != QRT_OK ||
        first < 0)
        return;
    int64_t t2 = now_us();
    can_->quick_stop();
    {
        std::lock_guard<std::mutex> lock(mu_);
        guard_stop_unreported_ = true;
    }
    log(LogLevel::warn,
        "the path being executed is blocked (segment %d): quick stop sent "
        "%.1f ms after the scan arrived (waiting and ingest %.1f, check "
        "%.1f ms)",
        first, 1e-3 * double(now_us() - received), 1e-3 * double(t1 - received),
        1e-3 * double(t2 - t1));
}

void Daemon::guard_loop(const RunFlags &flags)
{
    const std::atomic<bool> &stop = flags.stop;
    // ahead of the planner's mask threads where the system allows it (root
    // or CAP_SYS_NICE): the lowest real-time priority, and the guard sleeps
    // between scans, so it cannot starve anything else
    sched_param sp{};
    sp.sched_priority = 1;
    int rc = pthread_setschedparam(pthread_self(), SCHED_FIFO, &sp);
    log(rc == 0 ? LogLevel::info : LogLevel::debug, "guard thread: %s",
        rc == 0 ? "real-time priority (SCHED_FIFO 1)"
                : "normal priority (no permission for "
                  "SCHED_FIFO)");
    while (!stop) {
        guard_beat_us_ = CanLink::now_us();
        while (flags.freeze_guard && !stop) // --test-hooks: a stalled thread
            std::this_thread::sleep_for(std::chrono::milliseconds(10));
        std::map<std::string, PendingScan> scans;
        {
            std::unique_lock<std::mutex> lock(mu_);
            guard_wake_.wait_for(lock, std::chrono::milliseconds(GUARD_TICK_MS),
                                 [&] { return stop || !guard_scans_.empty(); });
            scans.swap(guard_scans_);
            guard_busy_ = !scans.empty();
        }
        int64_t received = 0;
        for (auto &kv : scans)
            received = std::max(received, kv.second.received_us);
        long invalid = 0;
        ingest(scans, &guard_picture_, false, &invalid);
        guard_beat_us_ = CanLink::now_us(); // a large scan is progress too
        CanLinkStatus cs = can_->status();
        guard_evidence(cs);
        if (!scans.empty()) {
            guard_check(can_->status(), received);
            std::lock_guard<std::mutex> lock(mu_);
            guard_busy_ = false;
            guard_idle_.notify_all();
        }
    }
}

// The CAN link thread's question, every millisecond: are the threads that
// guard motion going round their loops? No: the master stops the arm and
// its own heartbeat, so the drives stop even if this process hangs.
bool Daemon::host_alive(uint64_t now, std::string *why) const
{
    uint64_t guard = guard_beat_us_, planner = planner_beat_us_;
    if (now > guard && now - guard > uint64_t(opts_.guard_deadline_s * 1e6)) {
        *why = "the guard thread has been silent for " +
               std::to_string((now - guard) / 1000) + " ms";
        return false;
    }
    if (now > planner &&
        now - planner > uint64_t(opts_.planner_deadline_s * 1e6)) {
        *why = "the planner thread has been silent for " +
               std::to_string((now - planner) / 1000) + " ms";
        return false;
    }
    return true;
}

// --- the clock thread ------------------------------------------------------

void Daemon::clock_loop(const std::atomic<bool> &stop)
{
    int64_t next_status = now_us(), next_insecure_warning = next_status;
    while (!stop) {
        int64_t t = now_us();
        if (opts_.insecure_lcm && t >= next_insecure_warning) {
            next_insecure_warning = t + 60000000;
            log(LogLevel::warn,
                "--insecure-lcm: unsigned LCM messages are taken; anyone who "
                "can reach this computer's LCM port can move the arm");
        }
        if (can_) {
            CanLinkStatus cs = can_->status();
            if (cs.master.all_positions_known) {
                qrtplan::joint_state_t js{};
                js.utime = wall_us();
                for (int j = 0; j < 3; j++)
                    js.joints_deg[j] = cs.master.joints_deg[j];
                js.moving = cs.master.state == QRTCAN_MASTER_MOVING;
                js.drive_state = qrtcan_master_state_name(cs.master.state);
                lcm_.publish(opts_.joint_channel, &js);
            }
        }
        if (t >= next_status) {
            next_status = t + 1000000;
            qrtplan::daemon_status_t s{};
            s.utime = wall_us();
            std::string can_state = "off";
            if (can_) {
                CanLinkStatus cs = can_->status();
                can_state =
                    std::string(qrtcan_master_state_name(cs.master.state)) +
                    ", link " + cs.link;
                if (cs.master.reason != QRTCAN_REASON_NONE)
                    can_state += std::string(", ") +
                                 qrtcan_master_reason_name(cs.master.reason);
                s.can_frames_received = int64_t(cs.master.frames_in);
                s.can_frames_malformed = int64_t(cs.master.frames_malformed);
                s.can_frames_sent = int64_t(cs.frames_written);
                s.can_frames_dropped = int64_t(cs.master.frames_dropped);
                s.can_frames_unsent = int64_t(cs.frames_unsent);
                s.can_frames_withdrawn = int64_t(cs.master.frames_withdrawn);
                s.can_bus_errors = int64_t(cs.bus_errors);
                s.watchdog_trips = int64_t(cs.host_watchdog_trips);
            }
            {
                std::lock_guard<std::mutex> lock(mu_);
                s.uptime_s = double(t - started_us_) * 1e-6;
                s.scans_received = scans_received_;
                s.scans_dropped = scans_dropped_;
                s.scans_rejected = scans_rejected_;
                s.requests_received = requests_received_;
                s.requests_rejected = requests_rejected_;
                s.joint_states_rejected = joint_states_rejected_;
                s.plans_published = plans_published_;
                s.last_plan_latency_us = last_latency_us_;
                s.points_in_picture = int32_t(picture_points_);
                s.points_dropped = int32_t(points_dropped_);
                s.last_error = last_error_;
                s.scans_future = scans_future_;
                s.scans_stale = scans_stale_;
                s.scans_unknown_sensor = scans_unknown_sensor_;
                s.scans_over_budget = scans_over_budget_;
                s.returns_out_of_reach = returns_out_of_reach_;
                s.evidence_stops = evidence_stops_;
                s.messages_authenticated = messages_authenticated_;
                s.messages_unsigned = messages_unsigned_;
                const auto &r = auth_refused_;
                s.auth_unsigned = r[size_t(AuthRefusal::unsigned_message)];
                s.auth_malformed = r[size_t(AuthRefusal::malformed)];
                s.auth_unknown_sender = r[size_t(AuthRefusal::unknown_sender)];
                s.auth_bad_mac = r[size_t(AuthRefusal::bad_mac)];
                s.auth_replayed = r[size_t(AuthRefusal::replayed)];
                s.auth_counter_ahead = r[size_t(AuthRefusal::counter_ahead)];
                s.auth_not_permitted = r[size_t(AuthRefusal::not_permitted)];
            }
            s.lcm_input = auth_->accepts_unsigned() ? "unsigned accepted"
                                                    : "authenticated";
            s.lcm_datagrams_lost = lcm_datagrams_lost();
            s.log_lines_suppressed = log_lines_suppressed();
            s.can_state = can_state;
            lcm_.publish(opts_.status_channel, &s);
        }
        std::this_thread::sleep_for(std::chrono::milliseconds(50));
    }
}

// --- run -------------------------------------------------------------------

// Who may change what the arm does (auth.hpp). With --can the default is
// signed input only: without keys the daemon does not start, unless the
// operator asked for --insecure-lcm.
bool Daemon::start_auth()
{
    std::vector<SenderKey> keys;
    if (sodium_init() < 0) {
        log(LogLevel::error, "libsodium failed to start");
        return false;
    }
    if (!opts_.keys_dir.empty()) {
        std::string why;
        if (!load_keys(opts_.keys_dir, &keys, &why)) {
            log(LogLevel::error, "--keys: %s", why.c_str());
            return false;
        }
        std::string names;
        for (const SenderKey &k : keys)
            names += (names.empty() ? "" : ", ") + k.name + " (" +
                     role_name(k.role) + ")";
        log(LogLevel::info, "trusted senders: %s", names.c_str());
    } else if (!opts_.can_iface.empty() && !opts_.insecure_lcm) {
        log(LogLevel::error,
            "--can needs --keys DIR: only authenticated messages may move "
            "the arm (qrtpland --gen-key NAME --role ROLE makes keys; "
            "docs/security.md). --insecure-lcm takes unsigned messages "
            "from anyone on the network instead");
        return false;
    }
    bool accept_unsigned = keys.empty() || opts_.insecure_lcm;
    if (accept_unsigned && !opts_.insecure_lcm)
        log(LogLevel::warn, "no --keys: unsigned LCM messages are taken "
                            "(planning only; the status says so)");
    auth_.reset(new Authenticator(std::move(keys), accept_unsigned, wall_us(),
                                  int64_t(opts_.max_clock_skew_s * 1e6)));
    return true;
}

int Daemon::run(const RunFlags &flags)
{
    const std::atomic<bool> &stop = flags.stop;
    if (!lcm_.good()) {
        log(LogLevel::error, "cannot open LCM at %s", opts_.lcm_url.c_str());
        return 1;
    }
    int rc = qrt_planner_init(planner_.get(), &opts_.params);
    if (rc != QRT_OK) {
        log(LogLevel::error, "planner settings refused: %s", qrt_err_name(rc));
        return 2;
    }
    // what the daemon made of its options and config file, for whoever
    // has to tell why the arm moves as it does
    const qrt_arm &arm = opts_.params.arm;
    log(LogLevel::info,
        "arm: links %g,%g,%g m, radii %g,%g,%g m, limits %g..%g %g..%g "
        "%g..%g deg; tool %g m, radius %g m; grid %g deg, margin %g m, "
        "C-space margin %g deg, sampled fallback %ld draws",
        arm.link_m[0], arm.link_m[1], arm.link_m[2], arm.link_radius_m[0],
        arm.link_radius_m[1], arm.link_radius_m[2], arm.limit_deg[0][0],
        arm.limit_deg[0][1], arm.limit_deg[1][0], arm.limit_deg[1][1],
        arm.limit_deg[2][0], arm.limit_deg[2][1], arm.tool_m, arm.tool_radius_m,
        opts_.params.grid_deg, opts_.params.margin_m,
        opts_.params.cspace_margin_deg, opts_.params.sample_draws);
    if (!start_auth())
        return 2;
    if (!opts_.can_iface.empty()) {
        const qrtcan_master_config &c = opts_.can;
        log(LogLevel::info,
            "CAN %s: nodes %u,%u,%u, counts/deg %g,%g,%g, counts at 0 deg "
            "%ld,%ld,%ld, speed %g,%g,%g deg/s, accel %g,%g,%g deg/s^2",
            opts_.can_iface.c_str(), c.node[0], c.node[1], c.node[2],
            c.scale[0].counts_per_deg, c.scale[1].counts_per_deg,
            c.scale[2].counts_per_deg, long(c.scale[0].offset_counts),
            long(c.scale[1].offset_counts), long(c.scale[2].offset_counts),
            c.max_speed_deg_s[0], c.max_speed_deg_s[1], c.max_speed_deg_s[2],
            c.max_accel_deg_s2[0], c.max_accel_deg_s2[1],
            c.max_accel_deg_s2[2]);
        can_.reset(new CanLink(opts_.can_iface, opts_.can));
        std::string why;
        if (!can_->start(&why)) {
            log(LogLevel::error, "%s", why.c_str());
            return 2;
        }
        log(LogLevel::info, "CAN: drives on %s", opts_.can_iface.c_str());
        guard_planner_.reset(new_planner());
        qrt_planner_init(guard_planner_.get(), &opts_.params); // checked above
    }
    started_us_ = now_us();
    lcm_.subscribe(opts_.scan_channel + "(_.*)?", &Daemon::on_scan, this);
    lcm_.subscribe(opts_.cloud_channel + "(_.*)?", &Daemon::on_cloud, this);
    lcm_.subscribe(opts_.request_channel, &Daemon::on_request, this);
    if (!can_)
        lcm_.subscribe(opts_.joint_channel, &Daemon::on_joints, this);
    log(LogLevel::info, "listening on %s (scans %s*, clouds %s*, requests %s)",
        opts_.lcm_url.c_str(), opts_.scan_channel.c_str(),
        opts_.cloud_channel.c_str(), opts_.request_channel.c_str());
    std::thread planner([&] { planner_loop(flags); });
    std::thread clock([&] { clock_loop(stop); });
    std::thread guard;
    if (guard_planner_) {
        guard = std::thread([&] { guard_loop(flags); });
        // watched from now on: each thread has its full deadline to go
        // round its loop for the first time
        planner_beat_us_ = guard_beat_us_ = CanLink::now_us();
        can_->set_host_check([this](uint64_t now, std::string *why) {
            return host_alive(now, why);
        });
    }
    while (!stop)
        // the stop signal itself interrupts the wait: that is no failure
        if (lcm_.handleTimeout(100) < 0 && !stop) {
            log(LogLevel::error, "LCM receive failed; retrying");
            std::this_thread::sleep_for(std::chrono::milliseconds(100));
        }
    const uint64_t stop_seen_us = CanLink::now_us();
    if (can_) {
        // the arm stops before anything waits for a thread: a plan the
        // planner is finishing cannot reach the drives (the master takes no
        // path once shut down), and a thread slow to end cannot delay it
        can_->set_host_check(nullptr);
        can_->shutdown();
    }
    wake_.notify_all();
    guard_wake_.notify_all();
    planner.join();
    clock.join();
    if (guard.joinable())
        guard.join();
    const uint64_t joined_us = CanLink::now_us();
    if (can_) {
        // what the drives were last told, and when, for whoever reads why a
        // consumer fired at a shutdown
        const CanLinkStatus cs = can_->status();
        can_.reset(); // leaves the drives holding (docs/can-master.md)
        auto ms_after = [stop_seen_us](uint64_t t) {
            return t ? (double(t) - double(stop_seen_us)) * 1e-3 : 0.0;
        };
        log(LogLevel::info,
            "drives stopped: quick stop written %+.0f ms after the stop was "
            "seen, the last heartbeat at %+.0f ms, threads ended at %+.0f "
            "ms (%lu frames unsent, %lu write retries, %lu watchdog trips)",
            ms_after(cs.last_quick_stop_us), ms_after(cs.last_heartbeat_us),
            ms_after(joined_us), cs.frames_unsent, cs.write_retries,
            cs.host_watchdog_trips);
    }
    log(LogLevel::info, "shut down");
    return 0;
}

} // namespace qrt
