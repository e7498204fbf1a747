// libFuzzer target on qrtpland's message intake: the pre-decode size guard,
// the lcm-gen decoders of every type the daemon reads, and the scan and
// cloud checks and conversion (the same bytes tried as each type).
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <vector>

#include "decode.hpp"
#include "ingest.hpp"
#include "qrtplan/joint_state_t.hpp"
#include "qrtplan/plan_request_t.hpp"
#include "qrtplan/point_cloud_t.hpp"
#include "qrtplan/range_scan_t.hpp"

// Whatever decodes must encode, and that encoding must decode and encode to
// the same bytes again (the input itself may differ: a string with a NUL
// inside decodes to its first part).
template <class T> static void round_trip(const T &m, int used)
{
    std::vector<uint8_t> a(size_t(m.getEncodedSize()));
    if (used <= 0 || m.encode(a.data(), 0, int(a.size())) != int(a.size()))
        __builtin_trap();
    T again;
    if (qrt::safe_decode(&again, a.data(), int(a.size())) != int(a.size()))
        __builtin_trap();
    std::vector<uint8_t> b(size_t(again.getEncodedSize()));
    if (again.encode(b.data(), 0, int(b.size())) != int(b.size()) || a != b)
        __builtin_trap();
}

// A checked scan or cloud: what decodes round-trips, and its points are
// within reach, finite, and fit a picture exactly when they fit its budget.
static void points_hold(const qrt::SensorMessage &m)
{
    if (m.scan)
        round_trip(*m.scan, int(m.scan->getEncodedSize()));
    else
        round_trip(*m.cloud, int(m.cloud->getEncodedSize()));
    qrt::ScanPoints sp;
    if (!qrt::to_points(m, 100000, 1.0, &sp).empty())
        __builtin_trap(); // decode_sensor_message checked it already
    if (sp.xyz.size() % 3 != 0)
        __builtin_trap();
    for (size_t i = 0; i < sp.xyz.size(); i += 3)
        if (sp.xyz[i] * sp.xyz[i] + sp.xyz[i + 1] * sp.xyz[i + 1] +
                sp.xyz[i + 2] * sp.xyz[i + 2] >
            1.0 + 1e-9)
            __builtin_trap(); // beyond reach must be dropped
    // the nearest point beyond reach: a finite point beyond reach
    const long far = sp.out_of_reach;
    const double *f = sp.far_xyz;
    double f2 = f[0] * f[0] + f[1] * f[1] + f[2] * f[2];
    if (far > 0 && !(std::isfinite(f2) && f2 > 1.0 - 1e-9))
        __builtin_trap();
    qrt::Picture pic(0.5, 50000);
    long n = long(sp.xyz.size() / 3);
    bool fits = pic.add(std::move(sp), m.utime());
    if (fits != (n <= 50000) || pic.points() != (fits ? n : 0))
        __builtin_trap();
    std::vector<double> xyz;
    pic.gather(&xyz);
    for (double v : xyz)
        if (!(v == v))
            __builtin_trap(); // NaN must never reach the core
    // one far point for the sensor when its scan had any, that one
    pic.gather_far(&xyz);
    if (xyz.size() != (fits && far > 0 ? 3u : 0u) ||
        (!xyz.empty() && (xyz[0] != f[0] || xyz[1] != f[1] || xyz[2] != f[2])))
        __builtin_trap();
}

extern "C" int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    if (size > (1u << 20))
        return 0;
    const int n = int(size);
    for (qrt::SensorKind kind :
         {qrt::SensorKind::scan, qrt::SensorKind::cloud}) {
        qrt::SensorMessage m;
        if (qrt::decode_sensor_message(data, n, kind, 100000, &m).empty())
            points_hold(m);
    }
    qrtplan::plan_request_t req;
    int used = qrt::safe_decode(&req, data, n);
    if (used >= 0)
        round_trip(req, used);
    qrtplan::joint_state_t js;
    used =
        qrt::lcm_string_ok(data, n, 41) ? qrt::safe_decode(&js, data, n) : -1;
    // lcm-gen's C++ sizes a string by size() but writes it up to its first
    // NUL: round trips only hold for strings without one
    if (used >= 0 && js.drive_state.find('\0') == std::string::npos)
        round_trip(js, used);
    return 0;
}
