// SocketCAN transport and thread for the CiA 402 master; see can_link.hpp.
#include "can_link.hpp"

#include <cctype>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <ctime>

#include <linux/can.h>
#include <linux/can/error.h>
#include <linux/can/raw.h>
#include <net/if.h>
#include <poll.h>
#include <sys/ioctl.h>
#include <sys/socket.h>
#include <unistd.h>

namespace qrt
{

bool parse_node_ids(const std::string &text, unsigned ids[3])
{
    unsigned n = 0;
    return qrtcan_parse_node_list(text.c_str(), ids, 3, &n) == QRTCAN_OK &&
           n == 3;
}

bool parse_numbers(const std::string &text, double *out, int n)
{
    const char *p = text.c_str();
    for (int k = 0; k < n; k++) {
        char *end = nullptr;
        if (*p == '\0' || std::isspace(static_cast<unsigned char>(*p)))
            return false; // strtod would skip the space
        errno = 0;
        out[k] = std::strtod(p, &end);
        if (errno || end == p || !std::isfinite(out[k]) ||
            *end != (k + 1 < n ? ',' : '\0'))
            return false;
        p = end + 1;
    }
    return true;
}

bool parse_per_joint(const std::string &text, double out[3])
{
    if (text.find(',') != std::string::npos)
        return parse_numbers(text, out, 3);
    if (!parse_numbers(text, out, 1))
        return false;
    out[1] = out[2] = out[0];
    return true;
}

int finish_stdout(const char *program)
{
    if (std::fflush(stdout) != 0 || std::ferror(stdout)) {
        std::fprintf(stderr, "%s: stdout: write failed\n", program);
        return 2;
    }
    return 0;
}

bool all_within(const double x[3], double lo, double hi)
{
    return x[0] >= lo && x[0] <= hi && x[1] >= lo && x[1] <= hi && x[2] >= lo &&
           x[2] <= hi;
}

bool is_drive_setting(const std::string &key)
{
    return key == "counts-per-deg" || key == "offset-counts" ||
           key == "speed" || key == "accel";
}

bool drive_setting(qrtcan_master_config *cfg, const std::string &key,
                   const std::string &value, std::string *wanted)
{
    double v[3], size[3];
    bool ok = parse_per_joint(value, v);
    if (key == "counts-per-deg") {
        for (int j = 0; ok && j < 3; j++)
            size[j] = std::fabs(v[j]);
        if (!ok || !all_within(size, 1e-6, 1e7)) {
            *wanted = "non-zero counts per degree, 1e-6..1e7 in size, one "
                      "for every joint or three";
            return false;
        }
        for (int j = 0; j < 3; j++)
            cfg->scale[j].counts_per_deg = v[j];
    } else if (key == "offset-counts") {
        for (int j = 0; ok && j < 3; j++)
            ok = v[j] == std::floor(v[j]);
        if (!ok || !all_within(v, -1e9, 1e9)) {
            *wanted = "whole counts within 1e9 in size, one for every joint "
                      "or three";
            return false;
        }
        for (int j = 0; j < 3; j++)
            cfg->scale[j].offset_counts = int32_t(v[j]);
    } else { // speed or accel
        if (!ok || !all_within(v, 1e-3, 1e4)) {
            *wanted = "0.001..10000 degrees a second (squared), one for "
                      "every joint or three";
            return false;
        }
        for (int j = 0; j < 3; j++)
            (key == "speed" ? cfg->max_speed_deg_s : cfg->max_accel_deg_s2)[j] =
                v[j];
    }
    return true;
}

const char *const kLimitsDegWanted =
    "six numbers a0,a1,s0,s1,e0,e1 in -180..180, each low below its high";

bool parse_limits_deg(const std::string &text, double lim[3][2])
{
    double v[3][2];
    if (!parse_numbers(text, &v[0][0], 6) || !qrtcan_limits_valid(v))
        return false;
    std::memcpy(lim, v, sizeof v);
    return true;
}

// The waypoints as the C master takes them; false beyond its room.
static bool as_master_path(const std::vector<std::array<double, 3>> &waypoints,
                           double (*wp)[3])
{
    if (waypoints.empty() || waypoints.size() > QRTCAN_MASTER_MAX_WAYPOINTS)
        return false;
    for (size_t i = 0; i < waypoints.size(); i++)
        for (size_t j = 0; j < 3; j++)
            wp[i][j] = waypoints[i][j];
    return true;
}

int path_outside_limits(const qrtcan_master_config &cfg,
                        const std::vector<std::array<double, 3>> &waypoints)
{
    double wp[QRTCAN_MASTER_MAX_WAYPOINTS][3];
    if (!as_master_path(waypoints, wp))
        return -1; // set_path refuses these as QRTCAN_E_ARG
    return qrtcan_path_outside_limits(&cfg, wp, int(waypoints.size()));
}

namespace
{
constexpr uint64_t kReopenUs = 500000;   // retry a failed socket
constexpr uint64_t kNoBufferUs = 100000; // ENOBUFS this long is a bus fault
constexpr size_t kMaxPending = 256;
// on shutdown, how long the last quick stops may wait for room to be written
constexpr uint64_t kShutdownFlushUs = 200000;
} // namespace

uint64_t CanLink::now_us()
{
    timespec ts{};
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return uint64_t(ts.tv_sec) * 1000000u + uint64_t(ts.tv_nsec) / 1000u;
}

CanLink::CanLink(std::string iface, const qrtcan_master_config &cfg)
    : iface_(std::move(iface)), cfg_(cfg)
{
}

CanLink::~CanLink()
{
    if (thread_.joinable()) {
        shutdown();
        stop_ = true;
        thread_.join();
        // the thread no longer retries what the transmit queue refused
        // (EAGAIN, ENOBUFS): the quick stops must still reach the bus, so
        // wait for room a bounded time (a process that exits at once, as
        // qrtplan-exec does on a drive fault, lost the last stops)
        uint64_t until = now_us() + kShutdownFlushUs;
        while (!pending_.empty() && fd_ >= 0 && now_us() < until) {
            pollfd p{fd_, POLLOUT, 0};
            poll(&p, 1, 2);
            flush(now_us());
        }
    }
    close_socket();
}

bool CanLink::start(std::string *why)
{
    std::lock_guard<std::mutex> lock(mu_);
    uint64_t now = now_us();
    int rc = qrtcan_master_init(&master_, &cfg_, now);
    if (rc != QRTCAN_OK) {
        if (why)
            *why = std::string("CAN master configuration refused: ") +
                   qrtcan_strerror(rc);
        return false;
    }
    open_socket(now);
    qrtcan_master_start(&master_, now);
    thread_ = std::thread(&CanLink::run, this);
    return true;
}

void CanLink::open_socket(uint64_t now)
{
    close_socket();
    next_open_us_ = now + kReopenUs;
    int fd = socket(PF_CAN, SOCK_RAW | SOCK_NONBLOCK | SOCK_CLOEXEC, CAN_RAW);
    if (fd < 0) {
        link_ = std::string("no SocketCAN: ") + std::strerror(errno);
        return;
    }
    ifreq ifr{};
    if (iface_.size() >= sizeof ifr.ifr_name) {
        link_ = "interface name too long: " + iface_;
        ::close(fd);
        return;
    }
    std::memcpy(ifr.ifr_name, iface_.c_str(), iface_.size() + 1);
    if (ioctl(fd, SIOCGIFINDEX, &ifr) < 0) {
        link_ = iface_ + ": " + std::strerror(errno);
        ::close(fd);
        return;
    }
    can_err_mask_t errs =
        CAN_ERR_BUSOFF | CAN_ERR_CRTL | CAN_ERR_RESTARTED | CAN_ERR_TX_TIMEOUT;
    setsockopt(fd, SOL_CAN_RAW, CAN_RAW_ERR_FILTER, &errs, sizeof errs);
    sockaddr_can addr{};
    addr.can_family = AF_CAN;
    addr.can_ifindex = ifr.ifr_ifindex;
    if (bind(fd, reinterpret_cast<sockaddr *>(&addr), sizeof addr) < 0) {
        link_ = iface_ + ": bind: " + std::strerror(errno);
        ::close(fd);
        return;
    }
    fd_ = fd;
    link_ = "up";
}

void CanLink::close_socket()
{
    if (fd_ >= 0)
        ::close(fd_);
    fd_ = -1;
}

void CanLink::bus_error(uint64_t now, const std::string &why)
{
    bus_errors_++;
    link_ = why;
    discard_pending(pending_.size()); // stale; the master queues a quick stop
    qrtcan_master_bus_error(&master_, now);
}

void CanLink::discard_pending(size_t n)
{
    frames_unsent_ += n;
    pending_.erase(pending_.begin(), pending_.begin() + long(n));
}

void CanLink::flush(uint64_t now)
{
    qrtcan_frame taken[QRTCAN_MASTER_OUTBOX];
    int n = qrtcan_master_take_frames(&master_, taken, QRTCAN_MASTER_OUTBOX);
    pending_.insert(pending_.end(), taken, taken + n);
    if (pending_.size() > kMaxPending) // the bus has been refusing for long
        discard_pending(pending_.size() - kMaxPending);
    if (fd_ < 0)
        return;
    size_t written = 0;
    while (written < pending_.size()) {
        const qrtcan_frame &q = pending_[written];
        can_frame f{};
        f.can_id = q.id & CAN_SFF_MASK;
        f.can_dlc = q.dlc;
        std::memcpy(f.data, q.data, q.dlc);
        ssize_t rc = ::write(fd_, &f, sizeof f);
        if (rc == ssize_t(sizeof f)) {
            written++;
            frames_written_++;
            nobuf_since_ = 0;
            if (q.id >= 0x200 && q.id < 0x280 && q.dlc >= 2 &&
                (q.data[0] | (q.data[1] << 8)) == QRTCAN_CW_CMD_QUICK_STOP)
                last_quick_stop_us_ = now_us();
            if (q.id == QRTCAN_FN_HEARTBEAT + cfg_.master_node)
                last_heartbeat_us_ = now_us();
            continue;
        }
        if (errno == EAGAIN || errno == ENOBUFS || errno == EINTR) {
            write_retries_++;
            if (nobuf_since_ == 0)
                nobuf_since_ = now;
            else if (now - nobuf_since_ > kNoBufferUs) {
                nobuf_since_ = 0;
                pending_.erase(pending_.begin(),
                               pending_.begin() + long(written));
                bus_error(now, std::string("no buffer space for ") +
                                   std::to_string(kNoBufferUs / 1000) + " ms");
                return;
            }
            break;
        }
        std::string why = "down: " + std::string(std::strerror(errno));
        pending_.erase(pending_.begin(), pending_.begin() + long(written));
        close_socket();
        bus_error(now, why);
        return;
    }
    pending_.erase(pending_.begin(), pending_.begin() + long(written));
}

void CanLink::run()
{
    while (!stop_) {
        int fd;
        {
            std::lock_guard<std::mutex> lock(mu_);
            fd = fd_;
        }
        if (fd >= 0) {
            pollfd p{fd, POLLIN, 0};
            poll(&p, 1, 1);
        } else {
            usleep(1000);
        }
        std::unique_lock<std::mutex> lock(mu_);
        uint64_t now = now_us();
        if (fd_ < 0 && now >= next_open_us_)
            open_socket(now);
        for (int i = 0; fd_ >= 0 && i < 256; i++) {
            can_frame f{};
            ssize_t rc = ::read(fd_, &f, sizeof f);
            if (rc < 0) {
                if (errno != EAGAIN && errno != EINTR) {
                    std::string why =
                        "down: " + std::string(std::strerror(errno));
                    close_socket();
                    bus_error(now, why);
                }
                break;
            }
            if (rc != ssize_t(sizeof f))
                continue; // not a classic CAN frame
            if (f.can_id & CAN_ERR_FLAG) {
                if (f.can_id & CAN_ERR_BUSOFF)
                    bus_error(now, "bus-off");
                else if (f.can_id & CAN_ERR_RESTARTED)
                    link_ = "up";
                continue;
            }
            if (f.can_id & (CAN_EFF_FLAG | CAN_RTR_FLAG))
                continue; // CANopen here is 11-bit data frames only
            qrtcan_frame q{};
            q.id = f.can_id & CAN_SFF_MASK;
            q.dlc = f.can_dlc > 8 ? 8 : f.can_dlc;
            std::memcpy(q.data, f.data, q.dlc);
            if (link_ != "up")
                link_ = "up"; // frames flow again
            qrtcan_master_on_frame(&master_, &q, now);
        }
        std::string news = check_host(now);
        qrtcan_master_tick(&master_, now);
        flush(now);
        if (!news.empty()) {
            // after the stop is on the bus, and not holding the lock: a
            // slow stderr must not hold up the frames
            lock.unlock();
            std::fputs(news.c_str(), stderr);
            lock.lock();
        }
    }
}

void CanLink::set_host_check(HostCheck check)
{
    // removing the check leaves the master as it is: after a trip the arm
    // stays stopped and the heartbeat off (a shutdown follows)
    std::lock_guard<std::mutex> lock(mu_);
    host_check_ = std::move(check);
}

std::string CanLink::check_host(uint64_t now)
{
    if (!host_check_)
        return "";
    std::string why;
    bool alive = host_check_(now, &why);
    if (alive == host_alive_)
        return "";
    host_alive_ = alive;
    if (!alive) {
        host_watchdog_trips_++;
        discard_pending(pending_.size()); // set-points must not follow
    }
    qrtcan_master_set_host_alive(&master_, alive ? 1 : 0, now);
    if (!alive)
        return "qrtpland: error: host watchdog: " + why +
               ": quick stop, CAN heartbeat stopped\n";
    return "qrtpland: warn: host watchdog: the guarding threads are back; "
           "CAN heartbeat resumed, the arm stays stopped until the next "
           "path\n";
}

int CanLink::set_path(const std::vector<std::array<double, 3>> &waypoints)
{
    double wp[QRTCAN_MASTER_MAX_WAYPOINTS][3];
    if (!as_master_path(waypoints, wp))
        return QRTCAN_E_ARG;
    std::lock_guard<std::mutex> lock(mu_);
    uint64_t now = now_us();
    int rc = qrtcan_master_set_path(&master_, wp, int(waypoints.size()), now);
    if (rc == QRTCAN_OK) {
        qrtcan_master_tick(&master_, now);
        flush(now);
    }
    return rc;
}

void CanLink::quick_stop()
{
    std::lock_guard<std::mutex> lock(mu_);
    uint64_t now = now_us();
    discard_pending(pending_.size()); // set-points must not follow the stop
    qrtcan_master_quick_stop(&master_, now);
    flush(now);
}

void CanLink::shutdown()
{
    std::lock_guard<std::mutex> lock(mu_);
    uint64_t now = now_us();
    discard_pending(pending_.size()); // set-points must not follow the stop
    qrtcan_master_shutdown(&master_, now);
    flush(now);
}

CanLinkStatus CanLink::status() const
{
    std::lock_guard<std::mutex> lock(mu_);
    CanLinkStatus s;
    qrtcan_master_get_status(&master_, &s.master);
    s.link = link_;
    s.bus_errors = bus_errors_;
    s.write_retries = write_retries_;
    s.frames_written = frames_written_;
    s.frames_unsent = frames_unsent_;
    s.last_quick_stop_us = last_quick_stop_us_;
    s.last_heartbeat_us = last_heartbeat_us_;
    for (int i = 0; i < master_.n_waypoints; i++)
        s.path.push_back({master_.path_deg[i][0], master_.path_deg[i][1],
                          master_.path_deg[i][2]});
    s.host_watchdog_trips = host_watchdog_trips_;
    return s;
}

} // namespace qrt
