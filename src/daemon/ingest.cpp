#include "ingest.hpp"

#include "decode.hpp"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>

#include <Eigen/Dense>

namespace qrt
{

namespace
{

// The size guard of both messages: fingerprint 8, utime 8, sensor_id
// (length 4 + bytes), position 24, orientation 32, `between` bytes (a
// scan's max range), n 4, then 3 float arrays of n.
bool claims_fit(const void *buf, int size, long between, long max_returns,
                const char *what, std::string *why)
{
    const uint8_t *b = static_cast<const uint8_t *>(buf);
    long pos = 16;
    if (size < pos + 4) {
        *why = "truncated (" + std::to_string(size) + " bytes)";
        return false;
    }
    int32_t len = int32_t(lcm_u32(b + pos));
    if (len < 1 || len > size) {
        *why = "bad sensor_id length";
        return false;
    }
    pos += 4 + len + 24 + 32 + between;
    if (size < pos + 4) {
        *why = "truncated (" + std::to_string(size) + " bytes)";
        return false;
    }
    int32_t n = int32_t(lcm_u32(b + pos));
    pos += 4;
    if (n < 0 || long(n) > max_returns) {
        *why = "claims " + std::to_string(n) + " " + what + " (limit " +
               std::to_string(max_returns) + ")";
        return false;
    }
    if (size - pos < 12L * n) {
        *why = "claims " + std::to_string(n) + " " + what + " but holds " +
               std::to_string(size) + " bytes";
        return false;
    }
    return true;
}

// The header both messages share: sensor id, pose, count.
std::string check_header(const std::string &id, const double position[3],
                         const double orientation[4], int32_t n,
                         long max_returns, const char *what)
{
    if (id.size() > 64)
        return "sensor_id longer than 64 characters";
    for (char ch : id)
        if (static_cast<unsigned char>(ch) < 0x20 || ch == 0x7f)
            return "sensor_id with control characters";
    for (int i = 0; i < 3; i++)
        if (!std::isfinite(position[i]) || std::fabs(position[i]) > 1e3)
            return "non-finite or absurd sensor position";
    for (int i = 0; i < 4; i++)
        if (!std::isfinite(orientation[i]))
            return "non-finite orientation";
    Eigen::Quaterniond q(orientation[0], orientation[1], orientation[2],
                         orientation[3]);
    double norm = q.norm();
    if (std::fabs(norm - 1.0) > 1e-3)
        return "orientation is not a unit quaternion (norm " +
               std::to_string(norm) + ")";
    if (n < 0 || long(n) > max_returns)
        return std::string("too many ") + what + " (" + std::to_string(n) + ")";
    return "";
}

using Mask = Eigen::Array<bool, Eigen::Dynamic, 1>;

// Sensor-frame points (a column each) to the base frame, keeping the hits
// within reach_m of the base: the one conversion of scans and clouds. The
// header has been checked; a column that is not a hit may hold NaN.
void sensor_to_base(const double position[3], const double orientation[4],
                    const Eigen::Matrix3Xd &local, Mask hit, double reach_m,
                    ScanPoints *out)
{
    Eigen::Quaterniond q(orientation[0], orientation[1], orientation[2],
                         orientation[3]);
    Eigen::Matrix3d R = q.normalized().toRotationMatrix();
    Eigen::Vector3d t(position[0], position[1], position[2]);
    Eigen::Matrix3Xd world = (R * local).colwise() + t;
    // beyond reach: no capsule of the arm, grown by the margin, can touch it
    Eigen::ArrayXd dist = world.colwise().norm().array().transpose();
    Mask near = dist <= reach_m;
    Mask far = hit && !near;
    out->out_of_reach = long(far.count());
    if (out->out_of_reach > 0) {
        Eigen::Index best = -1;
        for (Eigen::Index i = 0; i < far.size(); i++)
            if (far(i) && (best < 0 || dist(i) < dist(best)))
                best = i;
        std::memcpy(out->far_xyz, world.col(best).data(), 3 * sizeof(double));
    }
    hit = hit && near;
    long kept = long(hit.count());
    out->xyz.resize(size_t(kept) * 3);
    long k = 0;
    for (Eigen::Index i = 0; i < local.cols(); i++)
        if (hit(i)) {
            std::memcpy(&out->xyz[size_t(k) * 3], world.col(i).data(),
                        3 * sizeof(double));
            k++;
        }
}

void start_points(const std::string &id, int64_t utime, ScanPoints *out)
{
    out->sensor = id;
    out->utime = utime;
    out->xyz.clear();
    out->no_hit = out->invalid = out->out_of_reach = 0;
    out->far_xyz[0] = out->far_xyz[1] = out->far_xyz[2] = 0.0;
}

} // namespace

bool scan_claims_fit(const void *buf, int size, long max_returns,
                     std::string *why)
{
    return claims_fit(buf, size, 4, max_returns, "returns", why);
}

bool cloud_claims_fit(const void *buf, int size, long max_returns,
                      std::string *why)
{
    return claims_fit(buf, size, 0, max_returns, "points", why);
}

std::string check_scan(const qrtplan::range_scan_t &s, long max_returns)
{
    std::string why = check_header(s.sensor_id, s.position_m, s.orientation,
                                   s.n, max_returns, "returns");
    if (!why.empty())
        return why;
    if (!std::isfinite(s.max_range_m) || s.max_range_m <= 0.0f)
        return "max_range_m must be positive and finite";
    return "";
}

std::string check_cloud(const qrtplan::point_cloud_t &c, long max_returns)
{
    return check_header(c.sensor_id, c.position_m, c.orientation, c.n,
                        max_returns, "points");
}

namespace
{

// The size guard, the decoder and the checks of one kind. The fingerprint
// first: a message of the other kind would otherwise be refused for what
// its bytes claim when read as this one.
template <class T>
std::string
decode_as(const void *buf, int size, long max_returns, const char *type,
          bool (*fits)(const void *, int, long, std::string *),
          std::string (*check)(const T &, long), std::shared_ptr<const T> *out)
{
    const uint8_t *b = static_cast<const uint8_t *>(buf);
    std::string why;
    if (size < 8 || int64_t(lcm_u64(b)) != T::getHash())
        return std::string("not a qrtplan.") + type +
               " (wrong type fingerprint, " + std::to_string(size) + " bytes)";
    if (!fits(buf, size, max_returns, &why))
        return why;
    auto msg = std::make_shared<T>();
    if (safe_decode(msg.get(), buf, size) < 0)
        return std::string("not a qrtplan.") + type + " (truncated, " +
               std::to_string(size) + " bytes)";
    why = check(*msg, max_returns);
    if (why.empty())
        *out = msg;
    return why;
}

} // namespace

std::string decode_sensor_message(const void *buf, int size, SensorKind kind,
                                  long max_returns, SensorMessage *out)
{
    *out = SensorMessage();
    if (kind == SensorKind::scan)
        return decode_as(buf, size, max_returns, "range_scan_t",
                         scan_claims_fit, check_scan, &out->scan);
    return decode_as(buf, size, max_returns, "point_cloud_t", cloud_claims_fit,
                     check_cloud, &out->cloud);
}

double arm_reach_m(const qrt_arm &arm, double margin_m)
{
    return qrt_arm_reach_m(&arm) + margin_m;
}

std::string scan_to_points(const qrtplan::range_scan_t &s, long max_returns,
                           double reach_m, ScanPoints *out)
{
    start_points(s.sensor_id, s.utime, out);
    std::string why = check_scan(s, max_returns);
    if (!why.empty())
        return why;
    const Eigen::Index n = s.n;
    if (n == 0)
        return "";
    Eigen::Map<const Eigen::ArrayXf> az(s.azimuth_rad.data(), n);
    Eigen::Map<const Eigen::ArrayXf> el(s.elevation_rad.data(), n);
    Eigen::Map<const Eigen::ArrayXf> r(s.range_m.data(), n);
    // a return counts when all three numbers are finite and 0 < r < max
    Mask finite = az.isFinite() && el.isFinite() && r.isFinite();
    Mask hit = finite && r > 0.0f && r < s.max_range_m;
    out->invalid = long((!finite || (finite && r <= 0.0f)).count());
    out->no_hit = long((finite && r >= s.max_range_m).count());
    // directions in the sensor frame, whole arrays at a time
    Eigen::ArrayXd ce = el.cast<double>().cos(), se = el.cast<double>().sin();
    Eigen::ArrayXd ca = az.cast<double>().cos(), sa = az.cast<double>().sin();
    Eigen::ArrayXd rd = r.cast<double>();
    Eigen::Matrix3Xd local(3, n);
    local.row(0) = (rd * ce * ca).matrix().transpose();
    local.row(1) = (rd * ce * sa).matrix().transpose();
    local.row(2) = (rd * se).matrix().transpose();
    sensor_to_base(s.position_m, s.orientation, local, hit, reach_m, out);
    return "";
}

std::string cloud_to_points(const qrtplan::point_cloud_t &c, long max_returns,
                            double reach_m, ScanPoints *out)
{
    start_points(c.sensor_id, c.utime, out);
    std::string why = check_cloud(c, max_returns);
    if (!why.empty())
        return why;
    const Eigen::Index n = c.n;
    if (n == 0)
        return "";
    Eigen::Map<const Eigen::ArrayXf> x(c.x_m.data(), n);
    Eigen::Map<const Eigen::ArrayXf> y(c.y_m.data(), n);
    Eigen::Map<const Eigen::ArrayXf> z(c.z_m.data(), n);
    // a point counts when its three coordinates are finite
    Mask hit = x.isFinite() && y.isFinite() && z.isFinite();
    out->invalid = long((!hit).count());
    Eigen::Matrix3Xd local(3, n);
    local.row(0) = x.cast<double>().matrix().transpose();
    local.row(1) = y.cast<double>().matrix().transpose();
    local.row(2) = z.cast<double>().matrix().transpose();
    sensor_to_base(c.position_m, c.orientation, local, hit, reach_m, out);
    return "";
}

std::string to_points(const SensorMessage &m, long max_returns, double reach_m,
                      ScanPoints *out)
{
    return m.scan ? scan_to_points(*m.scan, max_returns, reach_m, out)
                  : cloud_to_points(*m.cloud, max_returns, reach_m, out);
}

bool Picture::add(ScanPoints &&scan, int64_t now_us)
{
    const long n = long(scan.xyz.size() / 3);
    // what must stay: this scan and the newest scan of every other sensor
    long kept = n;
    for (const auto &kv : sensors_)
        if (kv.first != scan.sensor && !kv.second.empty())
            kept += long(kv.second.back().xyz.size() / 3);
    if (kept > max_points_)
        return false;
    int64_t &stamp = stamp_[scan.sensor];
    stamp = std::max(stamp, scan.utime);
    auto &q = sensors_[scan.sensor];
    if (window_s_ <= 0.0)
        while (!q.empty())
            pop_oldest(&q);
    points_ += n;
    q.push_back(std::move(scan));
    while (q.size() > kMaxScansPerSensor)
        pop_oldest(&q);
    // scans out of the window, by the daemon's clock: a scan stamped in
    // the future is refused before it gets here, so it cannot purge others
    if (window_s_ > 0.0) {
        // saturated: a clock (or, in the fuzzer, a stamp) near the bottom
        // of int64 must keep everything, not wrap round
        const int64_t window_us = int64_t(window_s_ * 1e6);
        const int64_t keep_from =
            now_us < std::numeric_limits<int64_t>::min() + window_us
                ? std::numeric_limits<int64_t>::min()
                : now_us - window_us;
        for (auto &kv : sensors_)
            while (kv.second.size() > 1 && kv.second.front().utime < keep_from)
                pop_oldest(&kv.second);
    }
    // over the budget: the oldest scans that are not their sensor's newest
    while (points_ > max_points_) {
        std::deque<ScanPoints> *oldest = nullptr;
        for (auto &kv : sensors_)
            if (kv.second.size() > 1 &&
                (!oldest || kv.second.front().utime < oldest->front().utime))
                oldest = &kv.second;
        if (!oldest)
            break; // cannot happen: the newest scans fit (checked above)
        pop_oldest(oldest);
    }
    return true;
}

void Picture::pop_oldest(std::deque<ScanPoints> *q)
{
    points_ -= long(q->front().xyz.size() / 3);
    q->pop_front();
}

std::map<std::string, int64_t>::const_iterator Picture::newest_stamp() const
{
    return std::max_element(
        stamp_.begin(), stamp_.end(),
        [](const auto &a, const auto &b) { return a.second < b.second; });
}

int64_t Picture::newest_utime() const
{
    return stamp_.empty() ? 0 : newest_stamp()->second;
}

void Picture::gather(std::vector<double> *xyz) const
{
    xyz->clear();
    xyz->reserve(size_t(points_) * 3);
    for (const auto &kv : sensors_)
        for (const auto &s : kv.second)
            xyz->insert(xyz->end(), s.xyz.begin(), s.xyz.end());
}

void Picture::gather_far(std::vector<double> *xyz) const
{
    xyz->clear();
    for (const auto &kv : sensors_) {
        const double *best = nullptr;
        double best2 = 0.0;
        for (const auto &s : kv.second) {
            if (s.out_of_reach == 0)
                continue;
            const double *p = s.far_xyz;
            double d2 = p[0] * p[0] + p[1] * p[1] + p[2] * p[2];
            if (!best || d2 < best2) {
                best = p;
                best2 = d2;
            }
        }
        if (best)
            xyz->insert(xyz->end(), best, best + 3);
    }
}

Evidence Picture::evidence(int64_t now_us,
                           const std::vector<std::string> &required,
                           int64_t max_age_us) const
{
    auto ms = [](int64_t us) { return std::to_string(us / 1000) + " ms"; };
    if (required.empty()) {
        if (stamp_.empty())
            return {"no_obstacle_data", "no scan has been received yet"};
        auto newest = newest_stamp();
        if (now_us - newest->second > max_age_us)
            return {"stale_obstacle_data",
                    "the newest scan (sensor '" + newest->first + "') is " +
                        ms(now_us - newest->second) + " old, over the " +
                        ms(max_age_us) + " allowed"};
        return {};
    }
    for (const std::string &id : required)
        if (stamp_.count(id) == 0)
            return {"no_obstacle_data",
                    "no scan from the required sensor '" + id + "' yet"};
    for (const std::string &id : required) {
        int64_t age = now_us - stamp_.at(id);
        if (age > max_age_us)
            return {"stale_obstacle_data",
                    "the required sensor '" + id + "' last scanned " + ms(age) +
                        " ago, over the " + ms(max_age_us) + " allowed"};
    }
    return {};
}

} // namespace qrt
