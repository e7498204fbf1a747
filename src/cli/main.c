/* qrtplan: the planning core on scene files. */
#define _XOPEN_SOURCE 700
#include <errno.h>
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "args.h"
#include "budget.h"
#include "end_check.h"
#include "gen.h"
#include "plan_json.h"
#include "qrtplan/qrtplan.h"
#include "scene.h"
#include "setpoints.h"

/* Every command's synopsis: on stderr for a usage error, and atop the
 * overview of `qrtplan --help`. Each command's own text (`qrtplan COMMAND
 * --help`) follows. */
static const char usage[] =
    "usage: qrtplan plan SCENE.json [-o PLAN.json] [--dijkstra] "
    "[--no-simplify]\n"
    "                    [--whole-mask] [--sample-draws N] "
    "[--max-memory BYTES]\n"
    "       qrtplan mask SCENE.json [-o MASK.json] [--max-memory BYTES]\n"
    "       qrtplan gen [--spheres N] [--points K] [--radius R] [--distance "
    "D]\n"
    "                   [--height Z] [--phase DEG] [--start A,S,E] [--goal "
    "A,S,E]\n"
    "                   [--pcd FILE | --pcd-ascii FILE] [-o SCENE.json]\n"
    "       qrtplan setpoints PLAN.json [--speed DEG_S] [--accel DEG_S2]\n"
    "                   [--period-ms MS] [--limits-deg a0,a1,s0,s1,e0,e1]\n"
    "                   [--wrap-alpha] [-o SETPOINTS.csv]\n"
    "       qrtplan COMMAND --help | --help | --version\n";

static const char overview[] =
    "\n"
    "plan   plan a scene file: the plan as JSON\n"
    "mask   the scene's blocked lattice nodes as JSON\n"
    "gen    write a scene of the paper's obstacle family (its Eq. 13)\n"
    "setpoints  a plan as a CSV of timed joint set-points\n"
    "\n"
    "qrtplan COMMAND --help prints that command's options. SCENE.json '-'\n"
    "reads the scene from standard input; '-o -' writes to standard output.\n"
    "Scene and plan files: docs/cli.md and docs/spec.md.\n"
    "\n"
    "Exit status: 0 for every well-formed scene, whatever the plan's status;\n"
    "2 with one line on stderr for input it cannot use, a bad option or\n"
    "output it cannot write.\n";

/* --max-memory, as plan and mask both take it */
#define MAX_MEMORY_HELP                                                        \
    "  --max-memory BYTES  the most memory it may hold (default 1G = 1 GiB;\n" \
    "                    bytes, or with K, M or G, powers of 1024; at least\n" \
    "                    16M, 36M in a host build): the planner's state\n"     \
    "                    (~4 MB, ~28 MB in a host build, whose --version\n"    \
    "                    says 524288 points) and 8 MiB for the program,\n"     \
    "                    then every buffer it allocates to read the scene,\n"  \
    "                    counted before it is made: the JSON text (at most\n"  \
    "                    1 GiB), its tree without the points array (~50 B\n"   \
    "                    a value), one point at a time, and ~140 KiB to\n"     \
    "                    stream a PCD file into the planner's fixed table,\n"  \
    "                    however many points it holds or claims. A scene\n"    \
    "                    that needs more is refused (exit 2). points_file\n"   \
    "                    must be a regular file (a FIFO or a device is\n"      \
    "                    refused at once).\n"

static const char plan_help[] =
    "usage: qrtplan plan SCENE.json [-o PLAN.json] [--dijkstra] "
    "[--no-simplify]\n"
    "                    [--whole-mask] [--sample-draws N] "
    "[--max-memory BYTES]\n"
    "\n"
    "Read a scene (arm, margins, grid_deg, points and/or a PCD points_file,\n"
    "start and goal as joints_deg or xyz_m, the latter optionally with\n"
    "the IK branch to take, e.g. \"ik\": {\"facing\": \"front\",\n"
    "\"elbow\": \"up\"}, and for an arm with a tool \"aim\": \"tool_tip\"\n"
    "to name the tool tip's point, not the end effector's) and plan,\n"
    "finding only the C-space mask nodes the plan reads, as it reads them\n"
    "(qrt_planner_plan_now): stats then say cells_blocked -1 and put the\n"
    "whole time under search. Writes the plan as JSON to PLAN.json or\n"
    "standard output. SCENE.json '-' reads standard input (its points_file\n"
    "then relative to the working directory).\n"
    "Scene and plan files: docs/spec.md, sections Scene and Plan.\n"
    "\n"
    "  -o PLAN.json      where to write the plan ('-': standard output)\n"
    "  --dijkstra        plain Dijkstra instead of A* (same cost, more work)\n"
    "  --no-simplify     return the lattice path without shortcuts\n"
    "  --sample-draws N  random configurations the sampled fallback may\n"
    "                    draw where the lattice has no path (default 2000;\n"
    "                    0: no fallback, the lattice's answer alone)\n"
    "  --whole-mask      build the whole mask first, then plan on it\n"
    "                    (qrt_planner_build_mask, qrt_planner_plan): the\n"
    "                    same plan, later; stats give cells_blocked and the\n"
    "                    mask's time under convert\n"
    "  --as-read         the default, accepted for older "
    "scripts\n" MAX_MEMORY_HELP "\n"
    "stats.time_us is this run's wall clock; in a fresh process its total\n"
    "is mostly the first touch of the planner's state (compare builds\n"
    "with tools/bench.sh, not with it).\n"
    "\n"
    "Exit status: 0 for every well-formed scene, whatever the plan's status\n"
    "(ok, no_path, start_blocked, goal_blocked, unreachable, capacity); 2\n"
    "with one line on stderr for input it cannot use, a bad option or\n"
    "output it cannot write.\n";

static const char mask_help[] =
    "usage: qrtplan mask SCENE.json [-o MASK.json] [--max-memory BYTES]\n"
    "\n"
    "Build the scene's whole C-space mask and write its blocked lattice\n"
    "nodes as JSON: grid_deg, n, lo_deg, alpha_wraps, cells_blocked and\n"
    "blocked, each an index (ia*ns + is)*ne + ie of the node whose joints\n"
    "are lo_deg + i*grid_deg. SCENE.json '-' reads standard input.\n"
    "\n"
    "  -o MASK.json      where to write the mask ('-': standard "
    "output)\n" MAX_MEMORY_HELP "\n"
    "Exit status: 0 for every well-formed scene; 2 with one line on stderr\n"
    "for input it cannot use, a bad option or output it cannot write.\n";

static const char gen_help[] =
    "usage: qrtplan gen [--spheres N] [--points K] [--radius R] [--distance "
    "D]\n"
    "                   [--height Z] [--phase DEG] [--start A,S,E] [--goal "
    "A,S,E]\n"
    "                   [--pcd FILE | --pcd-ascii FILE] [-o SCENE.json]\n"
    "\n"
    "Write a scene of the paper's obstacle family (its Eq. 13, Fig. 17).\n"
    "\n"
    "  --spheres N       spheres (default 1; 1..1000)\n"
    "  --points K        points per sphere (default 1444; 4..1e8), as k*k\n"
    "                    samples of Eq. 13's two angles, k = round(sqrt(K))\n"
    "  --radius R        each sphere's radius in metres (default 0.1;\n"
    "                    1e-6..1000)\n"
    "  --distance D      radius in metres of the circle around the base that\n"
    "                    carries the centres (default 0.6; |D| <= 1000)\n"
    "  --height Z        the centres' height in metres (default 0; |Z| <=\n"
    "                    1000)\n"
    "  --phase DEG       the first centre's bearing (default 180: behind the\n"
    "                    arm; |DEG| <= 1e6); the rest every 360/N degrees\n"
    "  --start A,S,E     start joints in degrees (default -100,0,0)\n"
    "  --goal A,S,E      goal joints in degrees (default 100,0,0)\n"
    "  --pcd FILE        write the points to a binary PCD file that the\n"
    "                    scene names in points_file\n"
    "  --pcd-ascii FILE  the same as an ASCII PCD file\n"
    "  -o SCENE.json     where to write the scene ('-': standard output)\n"
    "\n"
    "Exit status: 0 when the scene is written; 2 with one line on stderr\n"
    "for a value it refuses (outside the ranges above, more than 1e8 points\n"
    "in all, any number that is not finite), an unknown option or a file\n"
    "it cannot write.\n";

static const char setpoints_help[] =
    "usage: qrtplan setpoints PLAN.json [--speed DEG_S] [--accel DEG_S2]\n"
    "                   [--period-ms MS] [--limits-deg a0,a1,s0,s1,e0,e1]\n"
    "                   [--wrap-alpha] [-o SETPOINTS.csv]\n"
    "\n"
    "Write an \"ok\" plan (qrtplan plan's JSON; '-' reads standard input)\n"
    "as a CSV of timed joint set-points: the motion the CAN master\n"
    "(qrtpland --can, qrtplan-exec) gives its drives, segment by segment a\n"
    "straight line in joint space on a trapezoidal profile scaled by each\n"
    "joint's share of the move, so that all joints start and stop\n"
    "together (docs/can-master.md, \"The profile\"). Header\n"
    "t_s,alpha_deg,sigma_deg,eta_deg; a row every period from t_s 0 (the\n"
    "first waypoint), then one row at the end (the last waypoint). The\n"
    "segments follow each other without the master's pause between them.\n"
    "\n"
    "  --speed DEG_S[,S2,S3]   top joint speed, one for every joint or one\n"
    "                    each (30; 0.001..10000), as qrtpland's\n"
    "  --accel DEG_S2[,A2,A3]  joint acceleration = deceleration (60;\n"
    "                    0.001..10000), as qrtpland's\n"
    "  --period-ms MS    time between rows (10, the master's SYNC period;\n"
    "                    0.1..10000)\n"
    "  --limits-deg a0,a1,s0,s1,e0,e1  the joint limits the waypoints must\n"
    "                    keep to, as the master checks them (docs/spec.md\n"
    "                    section Arm: -180,180,-40,180,-180,140)\n"
    "  --wrap-alpha      alpha in (-180, 180] (default: continuous from the\n"
    "                    first waypoint's, as the master keeps its drive\n"
    "                    position, so a move across +-180 degrees never\n"
    "                    jumps by 360)\n"
    "  -o SETPOINTS.csv  where to write the CSV ('-': standard output)\n"
    "\n"
    "Exit status: 0 when the CSV is written; 2 with one line on stderr for\n"
    "a plan it cannot use (not ok, a waypoint outside the limits), a bad\n"
    "option or output it cannot write.\n";

static int fail(const char *file, const char *msg)
{
    if (file)
        fprintf(stderr, "qrtplan: %s: %s\n", file, msg);
    else
        fprintf(stderr, "qrtplan: %s\n", msg);
    return 2;
}

static long now_us(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (long)ts.tv_sec * 1000000L + ts.tv_nsec / 1000;
}

static FILE *open_output(const char *path)
{
    return path ? fopen(path, "w") : stdout;
}

/* "-o -" is standard output, as no -o is */
static const char *output_path(const char *arg)
{
    return strcmp(arg, "-") == 0 ? NULL : arg;
}

/* a scene path, or "-" for standard input */
static int is_scene_arg(const char *arg)
{
    return arg[0] != '-' || strcmp(arg, "-") == 0;
}

/* what messages call the scene */
static const char *scene_name(const char *path)
{
    return strcmp(path, "-") == 0 ? "standard input" : path;
}

static int close_output(FILE *f, const char *path)
{
    int bad = ferror(f);
    if (path)
        bad |= fclose(f) != 0;
    else
        bad |= fflush(f) != 0;
    return bad ? fail(path ? path : "stdout", "write failed") : 0;
}

/* The planner state (3.9 MiB in the board profile, 26.5 MiB in the host
 * profile's, docs/embedded.md): static, as on a board. */
static struct qrt_planner planner;

/* The memory budget: --max-memory, or this. Besides the planner's state
 * and what the readers allocate (counted), the program itself: its code,
 * the C library, stacks and stdio, well under 8 MiB (a plan's whole peak
 * resident set is 3-5 MB with a small scene, the planner's state
 * included). */
#define DEFAULT_MAX_MEMORY ((uint64_t)1 << 30)
#define PROGRAM_BYTES ((uint64_t)8 << 20)
/* the state and the program with a MiB to read a scene, in whole MiB; 16
 * MiB at least (a board profile's state needs less) */
#define MIN_STATE_MIB                                                          \
    ((sizeof planner + PROGRAM_BYTES + ((uint64_t)1 << 20) +                   \
      ((1u << 20) - 1)) >>                                                     \
     20)
#define MIN_MAX_MEMORY                                                         \
    ((MIN_STATE_MIB > 16 ? (uint64_t)MIN_STATE_MIB : (uint64_t)16) << 20)

/* --max-memory's value: 0, or an exit status. */
static int parse_max_memory(const char *arg, uint64_t *bytes)
{
    char min[32];
    if (budget_parse_bytes(arg, bytes)) {
        fprintf(stderr,
                "qrtplan: --max-memory: bad value '%.40s' (bytes, or with "
                "K, M or G: 512M, 2G)\n",
                arg);
        return 2;
    }
    if (*bytes < MIN_MAX_MEMORY) {
        budget_format(MIN_MAX_MEMORY, min, sizeof min);
        fprintf(stderr,
                "qrtplan: --max-memory: at least %s (the planner's state "
                "and the program)\n",
                min);
        return 2;
    }
    return 0;
}

static int fail_budget(const char *name)
{
    char limit[32];
    budget_format(budget_limit(), limit, sizeof limit);
    fprintf(stderr,
            "qrtplan: %s: needs more than the memory budget of %s "
            "(--max-memory)\n",
            name, limit);
    return 2;
}

/* The scene's points go straight into the planner as they are read. */
struct intake {
    int use_astar, simplify;
    long sample_draws;
    int init_rc, add_rc;
    long add_us;
};

static void intake_begin(void *ctx, const struct qrt_params *params)
{
    struct intake *in = (struct intake *)ctx;
    struct qrt_params p = *params;
    p.use_astar = in->use_astar;
    p.simplify = in->simplify;
    p.sample_draws = in->sample_draws;
    in->init_rc = qrt_planner_init(&planner, &p);
}

static void intake_add(void *ctx, const double *xyz, long n)
{
    struct intake *in = (struct intake *)ctx;
    long t0;
    if (in->init_rc != QRT_OK || in->add_rc != QRT_OK)
        return;
    t0 = now_us();
    in->add_rc = qrt_planner_add_points(&planner, xyz, n);
    in->add_us += now_us() - t0;
}

/* Scene -> points in the planner and (build_mask) the mask, within the
 * memory budget. Returns 0 or an exit status. */
static int prepare(const char *path, struct scene *sc, int use_astar,
                   int simplify, long sample_draws, int build_mask,
                   uint64_t max_memory, long *convert_us)
{
    char err[512];
    long t0;
    const char *name = scene_name(path);
    struct intake in;
    struct scene_sink sink;
    budget_init(max_memory, sizeof planner + PROGRAM_BYTES);
    in.use_astar = use_astar;
    in.simplify = simplify;
    in.sample_draws = sample_draws;
    in.init_rc = QRT_E_INVALID;
    in.add_rc = QRT_OK;
    in.add_us = 0;
    sink.begin = intake_begin;
    sink.add = intake_add;
    sink.ctx = &in;
    if (scene_load(path, &sink, sc, err, sizeof err))
        return budget_refused() ? fail_budget(name) : fail(name, err);
    if (in.init_rc == QRT_E_ABI) /* the core of another build linked in */
        return fail(NULL, qrt_abi_message(err, sizeof err));
    if (in.init_rc != QRT_OK)
        return fail(name, in.init_rc == QRT_E_TOO_BIG
                              ? "lattice larger than this build's tables "
                                "(coarser grid_deg or narrower limits)"
                              : "invalid arm, margins or grid_deg (alpha "
                                "wraps only with a grid that divides 360)");
    if (in.add_rc != QRT_OK)
        return fail(name, "obstacle points must be finite");
    t0 = now_us();
    if (build_mask)
        qrt_planner_build_mask(&planner);
    *convert_us = build_mask ? in.add_us + now_us() - t0 : 0;
    return 0;
}

static void end_check_points(void *ctx, const double *xyz, long n)
{
    end_check_add((struct end_check *)ctx, xyz, n);
}

/* A start or goal the core could not prove free: where it holds merged
 * points, the scene's points are read once more (they are never held
 * whole) and measured as given, so that the detail says "collides" only
 * when they collide; standard input cannot be read again, and the core's
 * sentence, which claims neither, stays. detail receives the sentence. */
static void measure_blocked_end(const char *path, const struct scene *sc,
                                uint64_t max_memory, struct qrt_plan *plan,
                                char *detail, size_t len)
{
    struct end_check c;
    struct scene again;
    struct scene_sink sink;
    char err[512];
    if (end_check_needed(plan)) {
        if (strcmp(path, "-") == 0)
            return;
        end_check_begin(&c, &planner, &sc->params.arm, plan, &sc->start,
                        &sc->goal);
        sink.begin = NULL;
        sink.add = end_check_points;
        sink.ctx = &c;
        budget_init(max_memory, sizeof planner + PROGRAM_BYTES);
        if (scene_load(path, &sink, &again, err, sizeof err))
            return; /* read once already: changed under us; claim nothing */
        plan->end_measured = 1;
        plan->end_clearance_m = end_check_clearance(&c);
    }
    if (!end_check_measured(plan))
        return;
    end_check_detail(
        plan, plan->status == QRT_STATUS_GOAL_BLOCKED ? &sc->goal : &sc->start,
        &sc->params, detail, len);
    plan->detail = detail;
}

static int cmd_plan(int argc, char **argv)
{
    char detail[END_CHECK_DETAIL_LEN];
    const char *scene_path = NULL, *out_path = NULL;
    struct scene sc;
    struct qrt_plan plan;
    struct stage_times t;
    int use_astar = 1, simplify = 1, whole_mask = 0, i, rc;
    long sample_draws = QRT_SAMPLE_DRAWS_DEFAULT;
    uint64_t max_memory = DEFAULT_MAX_MEMORY;
    long t_start = now_us(), t1;
    FILE *out;
    for (i = 0; i < argc; i++) {
        if (strcmp(argv[i], "-o") == 0 && i + 1 < argc)
            out_path = output_path(argv[++i]);
        else if (strcmp(argv[i], "--max-memory") == 0 && i + 1 < argc) {
            if ((rc = parse_max_memory(argv[++i], &max_memory)) != 0)
                return rc;
        } else if (strcmp(argv[i], "--dijkstra") == 0)
            use_astar = 0;
        else if (strcmp(argv[i], "--no-simplify") == 0)
            simplify = 0;
        else if (strcmp(argv[i], "--sample-draws") == 0 && i + 1 < argc) {
            if (args_long(argv[++i], 10, 0, QRT_SAMPLE_DRAWS_MAX,
                          &sample_draws) != 0)
                return fail(NULL, "plan: --sample-draws takes a whole number "
                                  "from 0 to 1000000");
        } else if (strcmp(argv[i], "--whole-mask") == 0)
            whole_mask = 1;
        else if (strcmp(argv[i], "--as-read") == 0)
            whole_mask = 0;
        else if (is_scene_arg(argv[i]) && !scene_path)
            scene_path = argv[i];
        else
            return fail(NULL, "plan: unexpected argument (see --help)");
    }
    if (!scene_path)
        return fail(NULL, "plan: no scene file given (see --help)");
    rc = prepare(scene_path, &sc, use_astar, simplify, sample_draws, whole_mask,
                 max_memory, &t.convert_us);
    if (rc)
        return rc;
    t1 = now_us();
    /* both give the same plan; asking only the nodes it reads is sooner */
    rc = whole_mask
             ? qrt_planner_plan(&planner, &sc.start, &sc.goal, &plan)
             : qrt_planner_plan_now(&planner, &sc.start, &sc.goal, &plan);
    t.search_us = now_us() - t1;
    if (rc != QRT_OK)
        return fail(scene_name(scene_path), qrt_err_name(rc));
    t1 = now_us();
    if (plan.status == QRT_STATUS_OK)
        (void)qrt_planner_certify_clearance(&planner, &plan);
    t.certify_us = now_us() - t1;
    measure_blocked_end(scene_path, &sc, max_memory, &plan, detail,
                        sizeof detail);
    out = open_output(out_path);
    if (!out)
        return fail(out_path, "cannot open for writing");
    t.total_us = now_us() - t_start;
    plan_write_json(out, &plan, &t);
    return close_output(out, out_path);
}

static int cmd_mask(int argc, char **argv)
{
    const char *scene_path = NULL, *out_path = NULL;
    struct scene sc;
    long convert_us;
    int i, rc;
    uint64_t max_memory = DEFAULT_MAX_MEMORY;
    FILE *out;
    for (i = 0; i < argc; i++) {
        if (strcmp(argv[i], "-o") == 0 && i + 1 < argc)
            out_path = output_path(argv[++i]);
        else if (strcmp(argv[i], "--max-memory") == 0 && i + 1 < argc) {
            if ((rc = parse_max_memory(argv[++i], &max_memory)) != 0)
                return rc;
        } else if (is_scene_arg(argv[i]) && !scene_path)
            scene_path = argv[i];
        else
            return fail(NULL, "mask: unexpected argument (see --help)");
    }
    if (!scene_path)
        return fail(NULL, "mask: no scene file given (see --help)");
    rc = prepare(scene_path, &sc, 1, 1, QRT_SAMPLE_DRAWS_DEFAULT, 1, max_memory,
                 &convert_us);
    if (rc)
        return rc;
    out = open_output(out_path);
    if (!out)
        return fail(out_path, "cannot open for writing");
    mask_write_json(out, qrt_planner_mask(&planner));
    return close_output(out, out_path);
}

static int write_pcd(const char *path, const double *xyz, long n, int ascii)
{
    FILE *f = fopen(path, ascii ? "w" : "wb");
    long i;
    if (!f)
        return -1;
    fprintf(f,
            "# .PCD v0.7 - written by qrtplan gen\nVERSION 0.7\n"
            "FIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nCOUNT 1 1 1\n"
            "WIDTH %ld\nHEIGHT 1\nVIEWPOINT 0 0 0 1 0 0 0\nPOINTS %ld\n"
            "DATA %s\n",
            n, n, ascii ? "ascii" : "binary");
    for (i = 0; i < n; i++) {
        float p[3];
        p[0] = (float)xyz[3 * i];
        p[1] = (float)xyz[3 * i + 1];
        p[2] = (float)xyz[3 * i + 2];
        if (ascii)
            fprintf(f, "%.9g %.9g %.9g\n", p[0], p[1], p[2]);
        else
            fwrite(p, sizeof p[0], 3, f);
    }
    return fclose(f) == 0 ? 0 : -1;
}

/* How the scene at scene_path should name the PCD file at pcd_path: the
 * bare file name when both sit in the same directory, else the PCD's
 * absolute path (points_file is resolved against the scene's directory). */
static int points_file_name(const char *pcd_path, const char *scene_path,
                            char *out, size_t len)
{
    char pcd_dir[4096], scene_dir[4096], real[4096];
    const char *slash = strrchr(pcd_path, '/');
    const char *name = slash ? slash + 1 : pcd_path;
    if (!realpath(pcd_path, real))
        return -1;
    snprintf(pcd_dir, sizeof pcd_dir, "%.*s", (int)(strrchr(real, '/') - real),
             real);
    if (scene_path && strrchr(scene_path, '/')) {
        char tmp[4096];
        snprintf(tmp, sizeof tmp, "%.*s",
                 (int)(strrchr(scene_path, '/') - scene_path), scene_path);
        if (!realpath(tmp[0] ? tmp : "/", scene_dir))
            return -1;
    } else if (!realpath(".", scene_dir)) {
        return -1;
    }
    snprintf(out, len, "%s", strcmp(pcd_dir, scene_dir) == 0 ? name : real);
    return 0;
}

static int cmd_gen(int argc, char **argv)
{
    struct sphere_layout L;
    double start[3] = {-100, 0, 0}, goal[3] = {100, 0, 0}, *xyz;
    const char *out_path = NULL, *pcd_path = NULL;
    int pcd_ascii = 0, i;
    long n;
    FILE *out;
    sphere_layout_default(&L);
    for (i = 0; i < argc; i++) {
        const char *a = argv[i], *v = i + 1 < argc ? argv[i + 1] : NULL;
        const char *need = "";
        int ok = 1;
        if (!v)
            return fail(NULL, "gen: option without a value (see --help)");
        i++;
        if (strcmp(a, "--spheres") == 0)
            ok = args_int(v, 10, 1, 1000, &L.spheres) == 0, need = "1..1000";
        else if (strcmp(a, "--points") == 0)
            ok = args_int(v, 10, 4, 100000000, &L.points) == 0, need = "4..1e8";
        else if (strcmp(a, "--radius") == 0)
            ok = args_number(v, 1e-6, 1e3, &L.radius_m) == 0,
            need = "1e-6..1000 m";
        else if (strcmp(a, "--distance") == 0)
            ok = args_number(v, -1e3, 1e3, &L.distance_m) == 0,
            need = "-1000..1000 m";
        else if (strcmp(a, "--height") == 0)
            ok = args_number(v, -1e3, 1e3, &L.height_m) == 0,
            need = "-1000..1000 m";
        else if (strcmp(a, "--phase") == 0)
            ok = args_number(v, -1e6, 1e6, &L.phase_deg) == 0,
            need = "-1e6..1e6 deg";
        else if (strcmp(a, "--start") == 0 || strcmp(a, "--goal") == 0)
            ok = args_numbers(v, 3, -1e6, 1e6, a[2] == 's' ? start : goal) == 0,
            need = "three finite degrees A,S,E";
        else if (strcmp(a, "-o") == 0)
            out_path = output_path(v);
        else if (strcmp(a, "--pcd") == 0 || strcmp(a, "--pcd-ascii") == 0) {
            pcd_path = v;
            pcd_ascii = a[5] == '-';
        } else
            return fail(NULL, "gen: unknown option (see --help)");
        if (!ok) {
            fprintf(stderr, "qrtplan: gen: bad value '%s' for %s (need %s)\n",
                    v, a, need);
            return 2;
        }
    }
    if ((double)L.spheres * sphere_side(&L) * sphere_side(&L) > 1e8)
        return fail(NULL, "gen: N x K beyond 1e8 points in all");
    n = sphere_layout_count(&L);
    xyz = malloc((size_t)n * 3 * sizeof *xyz);
    if (!xyz)
        return fail(NULL, "gen: out of memory");
    sphere_layout_points(&L, xyz);
    if (pcd_path && write_pcd(pcd_path, xyz, n, pcd_ascii)) {
        free(xyz);
        return fail(pcd_path, "cannot write");
    }
    out = open_output(out_path);
    if (!out) {
        free(xyz);
        return fail(out_path, "cannot open for writing");
    }
    fprintf(out,
            "{\n  \"version\": 1,\n  \"name\": \"%d sphere(s) x %ld "
            "points (paper Eq. 13)\",\n",
            L.spheres, n / L.spheres);
    if (pcd_path) {
        char name[4096];
        if (points_file_name(pcd_path, out_path, name, sizeof name)) {
            free(xyz);
            return fail(pcd_path, "cannot resolve its path");
        }
        fprintf(out, "  \"points_file\": \"%s\",\n", name);
    } else {
        fprintf(out, "  \"points\": [");
        for (i = 0; i < n; i++)
            fprintf(out, "%s[%.6f, %.6f, %.6f]",
                    i ? (i % 4 ? ", " : ",\n    ") : "\n    ", xyz[3 * i],
                    xyz[3 * i + 1], xyz[3 * i + 2]);
        fprintf(out, "\n  ],\n");
    }
    fprintf(out,
            "  \"start\": {\"joints_deg\": [%g, %g, %g]},\n"
            "  \"goal\": {\"joints_deg\": [%g, %g, %g]}\n}\n",
            start[0], start[1], start[2], goal[0], goal[1], goal[2]);
    free(xyz);
    return close_output(out, out_path);
}

static int cmd_setpoints(int argc, char **argv)
{
    static double wp[QRTCAN_MASTER_MAX_WAYPOINTS][3];
    struct setpoint_options o;
    const char *plan_path = NULL, *out_path = NULL;
    char err[256];
    int i, n;
    FILE *out;
    setpoints_default(&o);
    for (i = 0; i < argc; i++) {
        const char *a = argv[i], *v = i + 1 < argc ? argv[i + 1] : NULL;
        const char *need = NULL;
        double ms, lim[3][2];
        if (strcmp(a, "--wrap-alpha") == 0) {
            o.wrap_alpha = 1;
            continue;
        }
        if (is_scene_arg(a) && !plan_path) {
            plan_path = a;
            continue;
        }
        if (!v)
            return fail(NULL, "setpoints: unexpected argument or option "
                              "without a value (see --help)");
        i++;
        if (strcmp(a, "--speed") == 0 || strcmp(a, "--accel") == 0) {
            if (args_per_joint(v, 1e-3, 1e4,
                               a[2] == 's' ? o.speed_deg_s : o.accel_deg_s2))
                need = "0.001..10000, one for every joint or three";
        } else if (strcmp(a, "--period-ms") == 0) {
            if (args_number(v, 0.1, 1e4, &ms))
                need = "milliseconds in 0.1..10000";
            else
                o.period_s = ms * 1e-3;
        } else if (strcmp(a, "--limits-deg") == 0) {
            if (args_numbers(v, 6, -180.0, 180.0, &lim[0][0]) ||
                !qrtcan_limits_valid((const double(*)[2])lim))
                need = "six numbers a0,a1,s0,s1,e0,e1 in -180..180, each "
                       "low below its high";
            else
                memcpy(o.limit_deg, lim, sizeof lim);
        } else if (strcmp(a, "-o") == 0) {
            out_path = output_path(v);
        } else {
            return fail(NULL, "setpoints: unknown option (see --help)");
        }
        if (need) {
            fprintf(stderr,
                    "qrtplan: setpoints: bad value '%.40s' for %s (need "
                    "%s)\n",
                    v, a, need);
            return 2;
        }
    }
    if (!plan_path)
        return fail(NULL, "setpoints: no plan file given (see --help)");
    n = setpoints_read_plan(plan_path, wp, QRTCAN_MASTER_MAX_WAYPOINTS, err,
                            sizeof err);
    if (n < 0)
        return fail(scene_name(plan_path), err);
    out = open_output(out_path);
    if (!out)
        return fail(out_path, "cannot open for writing");
    if (setpoints_write(out, (const double(*)[3])wp, n, &o, err, sizeof err)) {
        if (out_path) {
            fclose(out);
            remove(out_path);
        }
        return fail(scene_name(plan_path), err);
    }
    return close_output(out, out_path);
}

/* A command's own text when any of its arguments asks for help. */
static int asks_help(int argc, char **argv)
{
    int i;
    for (i = 2; i < argc; i++)
        if (strcmp(argv[i], "--help") == 0 || strcmp(argv[i], "-h") == 0)
            return 1;
    return 0;
}

static int print_help(const char *a, const char *b)
{
    fputs(a, stdout);
    if (b)
        fputs(b, stdout);
    return close_output(stdout, NULL);
}

int main(int argc, char **argv)
{
    static const struct {
        const char *name, *help;
        int (*run)(int, char **);
    } commands[] = {{"plan", plan_help, cmd_plan},
                    {"mask", mask_help, cmd_mask},
                    {"gen", gen_help, cmd_gen},
                    {"setpoints", setpoints_help, cmd_setpoints}};
    size_t k;
    if (argc < 2) {
        fputs(usage, stderr);
        return 2;
    }
    if (strcmp(argv[1], "--help") == 0 || strcmp(argv[1], "-h") == 0)
        return print_help(usage, overview);
    if (strcmp(argv[1], "--version") == 0) {
        printf("qrtplan %s (lattice >= %d deg, %d points exact)\n",
               QRTPLAN_VERSION, QRT_GRID_DEG_MIN, QRT_MAX_POINTS);
        return close_output(stdout, NULL);
    }
    for (k = 0; k < sizeof commands / sizeof commands[0]; k++)
        if (strcmp(argv[1], commands[k].name) == 0)
            return asks_help(argc, argv) ? print_help(commands[k].help, NULL)
                                         : commands[k].run(argc - 2, argv + 2);
    fputs(usage, stderr);
    return 2;
}
