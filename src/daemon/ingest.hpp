// Range scans and point clouds -> base-frame points, and the obstacle
// picture they build.
#pragma once

#include <cstdint>
#include <deque>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include "qrtplan/arm.h"
#include "qrtplan/point_cloud_t.hpp"
#include "qrtplan/range_scan_t.hpp"

namespace qrt
{

// The points of one scan or cloud in the arm's base frame.
struct ScanPoints {
    std::string sensor;
    int64_t utime = 0;
    std::vector<double> xyz; // 3 per point
    long no_hit = 0;         // range >= max range (scans only)
    long invalid = 0;        // NaN/Inf angle, range or coordinate, range <= 0
    long out_of_reach = 0;   // farther from the base than the arm can come
    // the nearest of those (base frame), when out_of_reach > 0: the one
    // point beyond reach the planner is given, so that its certified
    // clearance counts the points it never sees (Picture::gather_far)
    double far_xyz[3] = {0.0, 0.0, 0.0};
};

// What a sensor sends: a range scan (azimuth, elevation, range) or a point
// cloud (x, y, z). Both carry the same header (stamp, sensor id, pose) and
// go through the same checks, the same conversion and the same picture; a
// sensor may send either, and its newest message of either kind is its
// entry. Exactly one pointer is set; shared by the planner's and the
// guard's queues, never copied.
enum class SensorKind { scan, cloud };
struct SensorMessage {
    std::shared_ptr<const qrtplan::range_scan_t> scan;
    std::shared_ptr<const qrtplan::point_cloud_t> cloud;
    const std::string &sensor_id() const
    {
        return scan ? scan->sensor_id : cloud->sensor_id;
    }
    int64_t utime() const
    {
        return scan ? scan->utime : cloud->utime;
    }
    const char *kind() const // "scan" or "cloud", for log lines
    {
        return scan ? "scan" : "cloud";
    }
};

// Untrusted bytes -> a checked message of the given kind: the size guard
// (*_claims_fit), the decoder, then the whole-message checks (check_scan,
// check_cloud). "" with *out set, or why the message is refused.
std::string decode_sensor_message(const void *buf, int size, SensorKind kind,
                                  long max_returns, SensorMessage *out);

// Whether the obstacle picture is evidence enough to move on: status ""
// when it is, else the plan status that says why not (no_obstacle_data,
// stale_obstacle_data) and one sentence naming the sensor.
struct Evidence {
    std::string status;
    std::string detail;
    bool fresh() const
    {
        return status.empty();
    }
};

// Before decoding: does the buffer hold the returns its count claims? The
// generated decoder sizes its arrays from the count before it checks the
// length, so a short message claiming 2^31 returns would allocate first.
bool scan_claims_fit(const void *buf, int size, long max_returns,
                     std::string *why);
bool cloud_claims_fit(const void *buf, int size, long max_returns,
                      std::string *why);

// The whole-message checks: sensor id printable and <= 64 characters, pose
// finite and a unit quaternion, count within max_returns; for a scan also
// max range positive. "" or why the message is refused.
std::string check_scan(const qrtplan::range_scan_t &scan, long max_returns);
std::string check_cloud(const qrtplan::point_cloud_t &cloud, long max_returns);

// Validates the pose and converts every return (vectorised with Eigen: the
// trigonometry runs over whole arrays, then one 3xN rotation). Points
// farther than reach_m from the base are dropped and counted: no part of
// the arm can come within its margin of them; the nearest of them is kept
// in far_xyz. Returns "" or why the whole
// scan is refused (non-finite or non-unit pose, bad max range, too many
// returns).
std::string scan_to_points(const qrtplan::range_scan_t &scan, long max_returns,
                           double reach_m, ScanPoints *out);
// The same for a cloud: a point is invalid when a coordinate is not finite;
// the pose, the rotation and the reach are scan_to_points' own code.
std::string cloud_to_points(const qrtplan::point_cloud_t &cloud,
                            long max_returns, double reach_m, ScanPoints *out);
// Whichever kind the message is.
std::string to_points(const SensorMessage &msg, long max_returns,
                      double reach_m, ScanPoints *out);

// How far from the base origin an obstacle point can matter: every point
// of the arm lies within the sum of the link and tool lengths of the
// origin, its surface a radius beyond (qrt_arm_reach_m), and the margin
// beyond that.
double arm_reach_m(const qrt_arm &arm, double margin_m);

// The obstacle picture: the newest scan of each sensor, or every scan of
// the last window_s seconds (by the daemon's clock), bounded in scans per
// sensor and in points altogether (max_points). It also remembers each
// sensor's newest accepted stamp, which is what freshness is judged by.
class Picture
{
  public:
    Picture(double window_s, long max_points)
        : window_s_(window_s), max_points_(max_points)
    {
    }
    // Adds the scan, evicting the oldest scans that are not their sensor's
    // newest while the picture holds more than max_points. False, with the
    // picture unchanged, when the scan does not fit beside the newest scan
    // of every other sensor: dropping those would erase what they saw.
    bool add(ScanPoints &&scan, int64_t now_us);
    void gather(std::vector<double> *xyz) const;
    // Per sensor, the nearest point beyond reach among its scans in the
    // picture (sensors with none give none): 3 doubles each. The planner
    // ignores them as out of reach but keeps their least distance from the
    // base, which bounds the clearance (qrt_planner_certify_clearance) from
    // every point ingest dropped. Not counted in points().
    void gather_far(std::vector<double> *xyz) const;
    long points() const
    {
        return points_;
    }
    int64_t newest_utime() const; // the newest accepted stamp, 0 if none
    // Fresh when every required sensor (any one sensor, if none is
    // required) has an accepted scan stamped at most max_age_us before
    // now_us; the stamps and now_us are the same clock (CLOCK_REALTIME).
    Evidence evidence(int64_t now_us, const std::vector<std::string> &required,
                      int64_t max_age_us) const;

    static constexpr size_t kMaxScansPerSensor = 64;

  private:
    void pop_oldest(std::deque<ScanPoints> *q);
    // the sensor with the newest accepted stamp; stamp_ must not be empty
    std::map<std::string, int64_t>::const_iterator newest_stamp() const;

    double window_s_;
    long max_points_;
    long points_ = 0;
    std::map<std::string, std::deque<ScanPoints>> sensors_;
    std::map<std::string, int64_t> stamp_; // newest accepted, per sensor
};

} // namespace qrt
