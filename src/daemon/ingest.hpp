// Range scans -> base-frame points, and the obstacle picture they build.
#pragma once

#include <cstdint>
#include <deque>
#include <map>
#include <string>
#include <vector>

#include "qrtplan/range_scan_t.hpp"

namespace qrt
{

// The points of one scan in the arm's base frame.
struct ScanPoints {
    std::string sensor;
    int64_t utime = 0;
    std::vector<double> xyz; // 3 per point
    long no_hit = 0;         // range >= max range
    long invalid = 0;        // NaN/Inf angle or range, range <= 0
};

// Before decoding: does the buffer hold the returns its count claims? The
// generated decoder sizes its arrays from the count before it checks the
// length, so a short message claiming 2^31 returns would allocate first.
bool scan_claims_fit(const void *buf, int size, long max_returns,
                     std::string *why);

// The whole-scan checks: pose finite and a unit quaternion, max range
// positive, count within max_returns. "" or why the scan is refused.
std::string check_scan(const qrtplan::range_scan_t &scan, long max_returns);

// Validates the pose and converts every return (vectorised with Eigen: the
// trigonometry runs over whole arrays, then one 3xN rotation). Returns ""
// or why the whole scan is refused (non-finite or non-unit pose, bad max
// range, too many returns).
std::string scan_to_points(const qrtplan::range_scan_t &scan, long max_returns,
                           ScanPoints *out);

// The newest scan of each sensor, or every scan of the last window_s
// seconds (by the scans' own utime), bounded in count and points.
class Picture
{
  public:
    explicit Picture(double window_s) : window_s_(window_s)
    {
    }
    void add(ScanPoints &&scan);
    void gather(std::vector<double> *xyz) const;
    long points() const;
    int64_t newest_utime() const
    {
        return newest_;
    }

    static constexpr size_t kMaxScansPerSensor = 64;

  private:
    double window_s_;
    int64_t newest_ = 0;
    std::map<std::string, std::deque<ScanPoints>> sensors_;
};

} // namespace qrt
