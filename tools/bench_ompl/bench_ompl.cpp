// qrtplan against OMPL on the same scenes, start, goal and collision rule
// (docs/spec.md section Collision: capsule links vs points, distance <
// radius + margin collides), interleaved repetition by repetition so that
// machine noise hits both alike.
//
//   bench_ompl [--repeats R] [--time-limit S] [--csv OUT]
//              [--replanning | --cold [--evict-mib M]] SCENE.json...
//
// Three regimes. In turn (the default): each planner's timed run follows the
// other planners' runs, so qrtplan always starts after PRM, which evicts its
// data and code, while RRTConnect starts after qrtplan's short run, with
// OMPL's code warm from PRM and the points just read by qrtplan. With
// --cold, every timed run (each planner's) starts after evict_bytes (256 MiB)
// have been written and read back, which evicts the caches' data and code
// alike: each planner then starts as a plan that runs once after other work
// does, and neither inherits the other's warm points. With
// --replanning, each planner (but RRT*) first plans, untimed, the scan
// before: the same scene with every coordinate moved by up to kJitterM, as
// a range sensor's noise moves it between scans; then the scene's points are
// copied, untimed, into a new array that the timed run reads, as a scan
// arrives just written. As in a loop that replans on every scan, each
// planner then starts with its own code and data in cache, and the scan.
//
// OMPL side: alpha is an SO2 (it wraps, and OMPL interpolates it the short
// way, as docs/spec.md section Guarantee asks), sigma and eta a 2-D real
// vector; states are checked against the points through a dense voxel index
// (5 cm cells, each listing its points; a link looks only at the cells its
// capsule's box touches); motions are checked discretely every 0.25 degree
// of joint motion (OMPL's DiscreteMotionValidator). Planners: RRTConnect and
// PRM (time to first solution: building the index and solve()), RRT* (path
// quality within the time limit); RRTConnect and RRT* with a deadline that
// starts no thread. Every path is written to the CSV as waypoints in degrees,
// for the independent oracle (tools/oracle.py, run by tools/bench_compare.py).
#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <memory>
#include <string>
#include <vector>

#include <ompl/base/PlannerTerminationCondition.h>
#include <ompl/base/SpaceInformation.h>
#include <ompl/base/spaces/RealVectorStateSpace.h>
#include <ompl/base/spaces/SO2StateSpace.h>
#include <ompl/geometric/SimpleSetup.h>
#include <ompl/geometric/planners/prm/PRM.h>
#include <ompl/geometric/planners/rrt/RRTConnect.h>
#include <ompl/geometric/planners/rrt/RRTstar.h>
#include <ompl/util/Console.h>

extern "C" {
#include "qrtplan/qrtplan.h"
#include "scene.h"
}

namespace ob = ompl::base;
namespace og = ompl::geometric;

namespace
{

constexpr double kDeg = M_PI / 180.0;
constexpr double kCell = 0.05;
constexpr double kStepDeg = 0.25;
constexpr double kJitterM = 0.002;
// What --cold writes before each timed run. The VM here reports a 480 MiB
// L3, but the planners' times stop rising between 64 and 256 MiB (a sweep
// of 4 MiB to 1 GiB, docs/performance.md "A race from cold caches").
size_t evict_bytes = size_t(256) << 20;

double now_ms()
{
    return std::chrono::duration<double, std::milli>(
               std::chrono::steady_clock::now().time_since_epoch())
        .count();
}

// Points in a dense grid of cells over their bounding box.
struct VoxelIndex {
    double lo[3]{};
    int n[3]{};
    std::vector<int> start; // per cell, into pts (CSR)
    std::vector<std::array<double, 3>> pts;

    void build(const double *xyz, long count)
    {
        double hi[3];
        for (int k = 0; k < 3; k++) {
            lo[k] = 1e9;
            hi[k] = -1e9;
        }
        for (long i = 0; i < count; i++)
            for (int k = 0; k < 3; k++) {
                lo[k] = std::min(lo[k], xyz[3 * i + k]);
                hi[k] = std::max(hi[k], xyz[3 * i + k]);
            }
        for (int k = 0; k < 3; k++)
            n[k] = count ? int((hi[k] - lo[k]) / kCell) + 1 : 0;
        std::vector<int> cell(size_t(std::max(count, 0L)));
        std::vector<int> fill(size_t(n[0]) * size_t(n[1]) * size_t(n[2]) + 1,
                              0);
        for (long i = 0; i < count; i++) {
            int c[3];
            for (int k = 0; k < 3; k++)
                c[k] =
                    std::min(n[k] - 1, int((xyz[3 * i + k] - lo[k]) / kCell));
            cell[size_t(i)] = (c[2] * n[1] + c[1]) * n[0] + c[0];
            fill[size_t(cell[size_t(i)]) + 1]++;
        }
        for (size_t i = 1; i < fill.size(); i++)
            fill[i] += fill[i - 1];
        start = fill;
        pts.resize(size_t(count));
        for (long i = 0; i < count; i++)
            pts[size_t(fill[size_t(cell[size_t(i)])]++)] = {
                xyz[3 * i], xyz[3 * i + 1], xyz[3 * i + 2]};
    }

    // Is any point closer than r to segment a-b?
    bool near_segment(const double *a, const double *b, double r) const
    {
        if (pts.empty())
            return false;
        int c0[3], c1[3];
        for (int k = 0; k < 3; k++) {
            c0[k] =
                std::max(0, int((std::min(a[k], b[k]) - r - lo[k]) / kCell));
            c1[k] = std::min(n[k] - 1,
                             int((std::max(a[k], b[k]) + r - lo[k]) / kCell));
            if (c1[k] < c0[k])
                return false;
        }
        double ab[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]};
        double len2 = ab[0] * ab[0] + ab[1] * ab[1] + ab[2] * ab[2];
        double reach = r + 0.8661 * kCell; // cell centre to corner
        for (int z = c0[2]; z <= c1[2]; z++)
            for (int y = c0[1]; y <= c1[1]; y++)
                for (int x = c0[0]; x <= c1[0]; x++) {
                    int id = (z * n[1] + y) * n[0] + x;
                    if (start[size_t(id)] == start[size_t(id) + 1])
                        continue;
                    double cc[3] = {lo[0] + (x + 0.5) * kCell,
                                    lo[1] + (y + 0.5) * kCell,
                                    lo[2] + (z + 0.5) * kCell};
                    if (dist2(cc, a, ab, len2) >= reach * reach)
                        continue;
                    for (int i = start[size_t(id)]; i < start[size_t(id) + 1];
                         i++)
                        if (dist2(pts[size_t(i)].data(), a, ab, len2) < r * r)
                            return true;
                }
        return false;
    }

    static double dist2(const double *p, const double *a, const double *ab,
                        double len2)
    {
        double ap[3] = {p[0] - a[0], p[1] - a[1], p[2] - a[2]};
        double t = len2 > 0
                       ? (ap[0] * ab[0] + ap[1] * ab[1] + ap[2] * ab[2]) / len2
                       : 0;
        t = t < 0 ? 0 : t > 1 ? 1 : t;
        double d = 0;
        for (int k = 0; k < 3; k++) {
            double e = ap[k] - t * ab[k];
            d += e * e;
        }
        return d;
    }
};

struct Checker {
    qrt_arm arm; // the collision arm (qrt_arm_collision_arm): links, tool
    double radius[3];
    VoxelIndex index;

    bool free(double a, double s, double e) const
    {
        double p[4][3] = {{0, 0, 0}};
        const double *l = arm.link_m;
        p[1][0] = l[0] * std::cos(a);
        p[1][1] = l[0] * std::sin(a);
        p[2][0] = p[1][0] + l[1] * std::cos(s) * std::cos(a);
        p[2][1] = p[1][1] + l[1] * std::cos(s) * std::sin(a);
        p[2][2] = l[1] * std::sin(s);
        p[3][0] = p[2][0] + l[2] * std::cos(s + e) * std::cos(a);
        p[3][1] = p[2][1] + l[2] * std::cos(s + e) * std::sin(a);
        p[3][2] = p[2][2] + l[2] * std::sin(s + e);
        for (int k = 0; k < 3; k++)
            if (index.near_segment(p[k], p[k + 1], radius[k]))
                return false;
        return true;
    }
};

double wrap180(double d)
{
    double r = std::fmod(d, 360.0);
    return r <= -180 ? r + 360 : r > 180 ? r - 360 : r;
}

double path_length(const std::vector<std::array<double, 3>> &w)
{
    double t = 0;
    for (size_t i = 1; i < w.size(); i++) {
        double d0 = wrap180(w[i][0] - w[i - 1][0]), d1 = w[i][1] - w[i - 1][1],
               d2 = w[i][2] - w[i - 1][2];
        t += std::sqrt(d0 * d0 + d1 * d1 + d2 * d2);
    }
    return t;
}

std::string path_json(const std::vector<std::array<double, 3>> &w)
{
    std::string s = "[";
    char buf[96];
    for (size_t i = 0; i < w.size(); i++) {
        std::snprintf(buf, sizeof buf, "%s[%.10g, %.10g, %.10g]", i ? ", " : "",
                      w[i][0], w[i][1], w[i][2]);
        s += buf;
    }
    return s + "]";
}

// The scan before: every coordinate moved by up to kJitterM, the same moves
// on every run (a fixed linear congruential sequence).
std::vector<double> scan_before(const double *xyz, long n)
{
    std::vector<double> out(xyz, xyz + 3 * std::max(n, 0L));
    uint32_t x = 12345u;
    for (double &v : out) {
        x = x * 1103515245u + 12345u;
        v += kJitterM * (2.0 * double(x >> 8) / double(1u << 24) - 1.0);
    }
    return out;
}

Checker checker_for(const scene &sc, const double *xyz, long n)
{
    Checker chk;
    qrt_arm_collision_arm(&sc.params.arm, &chk.arm);
    for (int k = 0; k < 3; k++)
        chk.radius[k] = chk.arm.link_radius_m[k] + sc.params.margin_m;
    chk.index.build(xyz, n);
    return chk;
}

// Writes and reads back a buffer larger than the caches, so that the next
// timed run finds none of its code or data there. The sum goes to a
// volatile, so the reads are not optimised away.
volatile unsigned long evict_sink;
void evict_caches(std::vector<unsigned char> &buf)
{
    if (buf.size() != evict_bytes)
        buf.assign(evict_bytes, 0);
    unsigned long sum = 0;
    for (size_t i = 0; i < buf.size(); i += 64)
        buf[i] = (unsigned char)(buf[i] + 1);
    for (size_t i = 0; i < buf.size(); i += 64)
        sum += buf[i];
    evict_sink = sum;
}

// A scene with its points held whole (the checker and the timed runs read
// them all; the CLI streams them into its planner instead).
struct held_scene {
    scene sc;
    std::vector<double> points;
};

void hold_points(void *ctx, const double *xyz, long n)
{
    auto *points = static_cast<std::vector<double> *>(ctx);
    points->insert(points->end(), xyz, xyz + 3 * n);
}

int load_scene(const char *path, held_scene *h, char *err, size_t err_len)
{
    scene_sink sink = {nullptr, hold_points, &h->points};
    h->points.clear();
    return scene_load(path, &sink, &h->sc, err, err_len);
}

// The points a timed run reads: the scene's own, or (replanning) a copy
// just made in scan, as a scan arrives.
const double *arrived(const held_scene &h, bool replanning,
                      std::vector<double> &scan)
{
    if (!replanning)
        return h.points.data();
    scan = h.points;
    return scan.data();
}

struct Result {
    bool ok = false;
    double ms = 0, length = 0;
    std::vector<std::array<double, 3>> path;
};

Result run_ompl(const scene &sc, const qrt_plan &ours, const Checker &chk,
                const std::string &name, double limit_s)
{
    auto so2 = std::make_shared<ob::SO2StateSpace>();
    auto rv = std::make_shared<ob::RealVectorStateSpace>(2);
    ob::RealVectorBounds b(2);
    const qrt_arm &arm = sc.params.arm;
    for (int j = 0; j < 2; j++) {
        b.setLow(j, arm.limit_deg[j + 1][0] * kDeg);
        b.setHigh(j, arm.limit_deg[j + 1][1] * kDeg);
    }
    rv->setBounds(b);
    auto space = std::make_shared<ob::CompoundStateSpace>();
    space->addSubspace(so2, 1.0);
    space->addSubspace(rv, 1.0);
    og::SimpleSetup ss(space);
    ss.setStateValidityChecker([&chk](const ob::State *st) {
        const auto *c = st->as<ob::CompoundState>();
        double a = c->as<ob::SO2StateSpace::StateType>(0)->value;
        const double *v = c->as<ob::RealVectorStateSpace::StateType>(1)->values;
        return chk.free(a, v[0], v[1]);
    });
    // the compound distance is the sum of |d alpha| and the Euclidean (sigma,
    // eta) step, so a step of kStepDeg in it moves no joint further
    ss.getSpaceInformation()->setStateValidityCheckingResolution(
        kStepDeg * kDeg / space->getMaximumExtent());
    ob::ScopedState<> start(space), goal(space);
    start[0] = ours.start_deg[0] * kDeg;
    start[1] = ours.start_deg[1] * kDeg;
    start[2] = ours.start_deg[2] * kDeg;
    goal[0] = ours.goal_deg[0] * kDeg;
    goal[1] = ours.goal_deg[1] * kDeg;
    goal[2] = ours.goal_deg[2] * kDeg;
    ss.setStartAndGoalStates(start, goal);
    auto si = ss.getSpaceInformation();
    if (name == "RRTConnect")
        ss.setPlanner(std::make_shared<og::RRTConnect>(si));
    else if (name == "PRM")
        ss.setPlanner(std::make_shared<og::PRM>(si));
    else
        ss.setPlanner(std::make_shared<og::RRTstar>(si));
    Result r;
    // The spaces and the planner are set up untimed: a user who replans on
    // every scan keeps them. Each planner gets the deadline it is faster
    // with (measured 2026-12-04). solve(seconds) polls its deadline from a
    // thread that sleeps in 1 ms slices and is joined at the end: about
    // 1.1 ms on every solve (RRTConnect on tunnel_1: 1.15-1.26 ms that way,
    // 0.26-0.38 ms with the thread-less deadline). PRM is the exception: it
    // checks for a solution on a thread of its own, and with the thread-less
    // deadline its medians rose from 1.3 to 9-46 ms in the tunnel and to
    // 400 ms on the shelf.
    ss.setup();
    double t0 = now_ms();
    ob::PlannerStatus st =
        name == "PRM" ? ss.solve(limit_s)
                      : ss.solve(ob::timedPlannerTerminationCondition(limit_s));
    r.ms = now_ms() - t0;
    r.ok = st == ob::PlannerStatus::EXACT_SOLUTION;
    if (!r.ok)
        return r;
    for (auto *s : ss.getSolutionPath().getStates()) {
        const auto *c = s->as<ob::CompoundState>();
        const double *v = c->as<ob::RealVectorStateSpace::StateType>(1)->values;
        r.path.push_back(
            {wrap180(c->as<ob::SO2StateSpace::StateType>(0)->value / kDeg),
             v[0] / kDeg, v[1] / kDeg});
    }
    r.length = path_length(r.path);
    return r;
}

} // namespace

int main(int argc, char **argv)
{
    int repeats = 5;
    double limit_s = 5.0;
    const char *csv_path = nullptr;
    bool replanning = false, cold = false;
    std::vector<const char *> scenes;
    std::vector<unsigned char> evict_buf;
    for (int i = 1; i < argc; i++) {
        if (!std::strcmp(argv[i], "--repeats") && i + 1 < argc)
            repeats = std::max(1, std::atoi(argv[++i]));
        else if (!std::strcmp(argv[i], "--time-limit") && i + 1 < argc)
            limit_s = std::atof(argv[++i]);
        else if (!std::strcmp(argv[i], "--csv") && i + 1 < argc)
            csv_path = argv[++i];
        else if (!std::strcmp(argv[i], "--replanning"))
            replanning = true;
        else if (!std::strcmp(argv[i], "--cold"))
            cold = true;
        else if (!std::strcmp(argv[i], "--evict-mib") && i + 1 < argc) {
            char *end = nullptr;
            long mib = std::strtol(argv[++i], &end, 10);
            if (*end || mib < 1 || mib > 65536) {
                std::fprintf(stderr,
                             "bench_ompl: --evict-mib wants 1..65536, "
                             "not '%s'\n",
                             argv[i]);
                return 2;
            }
            evict_bytes = size_t(mib) << 20;
        } else if (argv[i][0] == '-') {
            std::fprintf(stderr,
                         "usage: bench_ompl [--repeats R] [--time-limit S] "
                         "[--csv OUT] [--replanning | --cold [--evict-mib M]] "
                         "SCENE.json...\n");
            return 2;
        } else
            scenes.push_back(argv[i]);
    }
    if (replanning && cold) {
        std::fprintf(stderr,
                     "bench_ompl: --replanning and --cold are two regimes; "
                     "give one\n");
        return 2;
    }
    ompl::msg::setLogLevel(ompl::msg::LOG_NONE);
    FILE *csv = csv_path ? std::fopen(csv_path, "w") : stdout;
    if (!csv) {
        std::perror(csv_path);
        return 1;
    }
    std::fprintf(
        csv, "scene,planner,rep,success,time_ms,length_deg,waypoints,path\n");
    static qrt_planner pl;
    static qrt_plan plan;
    const char *planners[] = {"RRTConnect", "PRM", "RRTstar"};
    for (size_t si = 0; si < scenes.size(); si++) {
        held_scene held;
        const scene &sc = held.sc;
        char err[256];
        if (load_scene(scenes[si], &held, err, sizeof err) != 0) {
            std::fprintf(stderr, "bench_ompl: %s\n", err);
            return 1;
        }
        std::fprintf(stderr, "\r[%zu/%zu] %s          ", si + 1, scenes.size(),
                     scenes[si]);
        const std::vector<double> before =
            replanning ? scan_before(held.points.data(), sc.n_points)
                       : std::vector<double>();
        for (int rep = 0; rep < repeats; rep++) {
            // ours, end to end: points, then a plan that finds only the
            // mask nodes it reads (the straight motion first, on its own
            // rows; the search's nodes as it takes them)
            if (replanning) {
                qrt_planner_init(&pl, &sc.params);
                qrt_planner_add_points(&pl, before.data(), sc.n_points);
                qrt_planner_plan_now(&pl, &sc.start, &sc.goal, &plan);
            }
            std::vector<double> scan;
            const double *points = arrived(held, replanning, scan);
            if (cold)
                evict_caches(evict_buf);
            double t0 = now_ms();
            qrt_planner_init(&pl, &sc.params);
            qrt_planner_add_points(&pl, points, sc.n_points);
            qrt_planner_plan_now(&pl, &sc.start, &sc.goal, &plan);
            double ms = now_ms() - t0;
            std::vector<std::array<double, 3>> w;
            for (int i = 0; i < plan.n_waypoints; i++)
                w.push_back({plan.waypoints_deg[i][0], plan.waypoints_deg[i][1],
                             plan.waypoints_deg[i][2]});
            bool ok = plan.status == QRT_STATUS_OK;
            std::fprintf(csv, "%s,qrtplan,%d,%d,%.4f,%.4f,%zu,\"%s\"\n",
                         scenes[si], rep, ok, ms, ok ? plan.cost_deg : 0.0,
                         w.size(), path_json(w).c_str());
            // a start or goal qrtplan cannot connect (blocked, or free but
            // stranded off the lattice) is its failure, not the scene's:
            // OMPL gets the same joints. Only with no joints at all (out of
            // reach, a bad request) is there nothing to compare.
            if (plan.status != QRT_STATUS_OK &&
                plan.status != QRT_STATUS_NO_PATH &&
                plan.status != QRT_STATUS_START_BLOCKED &&
                plan.status != QRT_STATUS_GOAL_BLOCKED)
                break;
            if (plan.status == QRT_STATUS_START_BLOCKED) {
                // the goal was never resolved: only a goal in joints is
                // known without qrtplan's IK choice
                if (sc.goal.kind != QRT_TARGET_JOINTS)
                    break;
                for (int k = 0; k < 3; k++)
                    plan.goal_deg[k] = sc.goal.value[k];
            }
            // OMPL, the index built inside the timed part as ours converts
            for (const char *name : planners) {
                if (!std::strcmp(name, "RRTstar") && rep > 0)
                    continue; // quality, once per scene
                double limit = !std::strcmp(name, "RRTstar")
                                   ? std::min(limit_s, 1.0)
                                   : limit_s;
                if (replanning && std::strcmp(name, "RRTstar"))
                    run_ompl(sc, plan,
                             checker_for(sc, before.data(), sc.n_points), name,
                             limit);
                const double *points = arrived(held, replanning, scan);
                if (cold)
                    evict_caches(evict_buf);
                double t1 = now_ms();
                Checker chk = checker_for(sc, points, sc.n_points);
                double build = now_ms() - t1;
                Result r = run_ompl(sc, plan, chk, name, limit);
                std::fprintf(csv, "%s,%s,%d,%d,%.4f,%.4f,%zu,\"%s\"\n",
                             scenes[si], name, rep, r.ok, r.ms + build,
                             r.length, r.path.size(),
                             path_json(r.path).c_str());
            }
        }
        std::fflush(csv);
    }
    std::fprintf(stderr, "\n");
    if (csv != stdout)
        std::fclose(csv);
    return 0;
}
