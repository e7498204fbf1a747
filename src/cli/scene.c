#define _POSIX_C_SOURCE 200809L
/* Scene loading and validation: every field's type, length and range. */
#include "scene.h"

#include <errno.h>
#include <fcntl.h>
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <sys/types.h>
#include <unistd.h>

#include "budget.h"
#include "json.h"
#include "pcd.h"

/* Larger files are refused. */
#define SCENE_MAX_FILE_BYTES ((size_t)1 << 30)

/* What a file that is not a regular one is, for messages. */
static const char *file_kind(mode_t mode)
{
    if (S_ISFIFO(mode))
        return "a FIFO";
    if (S_ISCHR(mode))
        return "a character device";
    if (S_ISBLK(mode))
        return "a block device";
    if (S_ISDIR(mode))
        return "a directory";
    if (S_ISSOCK(mode))
        return "a socket";
    return "not a regular file";
}

static int too_large(const char *name, char *err, size_t err_len)
{
    snprintf(err, err_len, "%s is larger than %d MiB", name,
             (int)(SCENE_MAX_FILE_BYTES >> 20));
    return -1;
}

int read_whole_file(const char *path, char **buf, size_t *len, char *err,
                    size_t err_len)
{
    /* "-": standard input, as a pipe gives it */
    int from_stdin = strcmp(path, "-") == 0, failed = 1;
    int fd = from_stdin ? STDIN_FILENO : open(path, O_RDONLY | O_NOCTTY);
    const char *name = from_stdin ? "standard input" : path;
    struct stat st;
    size_t cap = (size_t)1 << 16, n = 0;
    char *b = NULL;
    if (fd < 0) {
        snprintf(err, err_len, "cannot open %s: %s", path, strerror(errno));
        return -1;
    }
    if (fstat(fd, &st) != 0) {
        snprintf(err, err_len, "cannot read %s: %s", name, strerror(errno));
        goto out;
    }
    /* a device would be read for ever (/dev/zero) or to its end (a disk);
     * a terminal is someone typing */
    if (S_ISBLK(st.st_mode) || (S_ISCHR(st.st_mode) && !isatty(fd))) {
        snprintf(err, err_len, "%s is %s, not a regular file or a pipe", name,
                 file_kind(st.st_mode));
        goto out;
    }
    if (S_ISREG(st.st_mode)) { /* room for it all, the NUL and one more */
        if ((uint64_t)st.st_size >= SCENE_MAX_FILE_BYTES - 1) {
            too_large(name, err, err_len);
            goto out;
        }
        cap = (size_t)st.st_size + 2;
    }
    b = budget_malloc(cap);
    if (!b) {
        snprintf(err, err_len, "out of memory reading %s", name);
        goto out;
    }
    for (;;) {
        ssize_t got;
        if (n == cap - 1) {
            size_t ncap =
                cap > SCENE_MAX_FILE_BYTES / 2 ? SCENE_MAX_FILE_BYTES : cap * 2;
            char *grown;
            if (cap >= SCENE_MAX_FILE_BYTES) {
                too_large(name, err, err_len);
                goto out;
            }
            grown = budget_realloc(b, ncap);
            if (!grown) {
                snprintf(err, err_len, "out of memory reading %s", name);
                goto out;
            }
            b = grown;
            cap = ncap;
        }
        got = read(fd, b + n, cap - 1 - n);
        if (got < 0 && errno == EINTR)
            continue;
        if (got < 0) {
            snprintf(err, err_len, "cannot read %s", name);
            goto out;
        }
        if (got == 0)
            break;
        n += (size_t)got;
    }
    b[n] = '\0';
    *buf = b;
    *len = n;
    b = NULL;
    failed = 0;
out:
    budget_free(b);
    if (!from_stdin)
        close(fd);
    return failed ? -1 : 0;
}

/* Exactly n numbers, each within [lo, hi]. */
static int get_numbers(const struct json *v, const char *what, size_t n,
                       double lo, double hi, double *out, char *err,
                       size_t err_len)
{
    size_t i;
    if (!v || v->type != JSON_ARRAY || v->count != n) {
        snprintf(err, err_len, "%s must be an array of %zu numbers", what, n);
        return -1;
    }
    for (i = 0; i < n; i++) {
        if (v->items[i].type != JSON_NUMBER) {
            snprintf(err, err_len, "%s[%zu] must be a number, not %s", what, i,
                     json_type_name(v->items[i].type));
            return -1;
        }
        if (v->items[i].number < lo || v->items[i].number > hi) {
            snprintf(err, err_len, "%s[%zu] = %g is outside [%g, %g]", what, i,
                     v->items[i].number, lo, hi);
            return -1;
        }
        out[i] = v->items[i].number;
    }
    return 0;
}

static int get_number(const struct json *obj, const char *key, double lo,
                      double hi, double *out, char *err, size_t err_len)
{
    const struct json *v = json_get(obj, key);
    if (!v)
        return 0; /* optional: keep the default */
    if (v->type != JSON_NUMBER) {
        snprintf(err, err_len, "%s must be a number, not %s", key,
                 json_type_name(v->type));
        return -1;
    }
    if (v->number < lo || v->number > hi) {
        snprintf(err, err_len, "%s = %g is outside [%g, %g]", key, v->number,
                 lo, hi);
        return -1;
    }
    *out = v->number;
    return 0;
}

/* Refuses a key of obj that is not in allowed (NULL-terminated), naming it
 * (cut to 64 bytes, so that the list fits) and every valid key. */
static int only_keys(const struct json *obj, const char *what,
                     const char *const *allowed, char *err, size_t err_len)
{
    size_t i, used;
    for (i = 0; i < obj->count; i++) {
        const char *const *a;
        for (a = allowed; *a; a++)
            if (strcmp(obj->keys[i], *a) == 0)
                break;
        if (*a)
            continue;
        snprintf(err, err_len,
                 "unknown field \"%.64s\" in %s (valid: ", obj->keys[i], what);
        for (a = allowed; *a; a++) {
            used = strlen(err);
            snprintf(err + used, err_len - used, "%s%s",
                     a == allowed ? "" : ", ", *a);
        }
        used = strlen(err);
        snprintf(err + used, err_len - used, ")");
        return -1;
    }
    return 0;
}

/* One required number of obj, named what in messages, within [lo, hi]. */
static int get_required(const struct json *obj, const char *key,
                        const char *what, double lo, double hi, double *out,
                        char *err, size_t err_len)
{
    const struct json *v = json_get(obj, key);
    if (!v) {
        snprintf(err, err_len, "missing field \"%s\" in %s", key, what);
        return -1;
    }
    if (v->type != JSON_NUMBER) {
        snprintf(err, err_len, "%s.%s must be a number, not %s", what, key,
                 json_type_name(v->type));
        return -1;
    }
    if (v->number < lo || v->number > hi) {
        snprintf(err, err_len, "%s.%s = %g is outside [%g, %g]", what, key,
                 v->number, lo, hi);
        return -1;
    }
    *out = v->number;
    return 0;
}

/* arm.tool: a capsule on link 3 beyond the end effector (docs/spec.md
 * section Arm, Tool). */
static int parse_tool(const struct json *tool, struct qrt_arm *out, char *err,
                      size_t err_len)
{
    static const char *const keys[] = {"length_m", "radius_m", NULL};
    if (tool->type != JSON_OBJECT) {
        snprintf(err, err_len,
                 "arm.tool must be an object with length_m and radius_m, not "
                 "%s",
                 json_type_name(tool->type));
        return -1;
    }
    if (only_keys(tool, "arm.tool", keys, err, err_len) ||
        get_required(tool, "length_m", "arm.tool", 0.0, 100.0, &out->tool_m,
                     err, err_len) ||
        get_required(tool, "radius_m", "arm.tool", 0.0, 10.0,
                     &out->tool_radius_m, err, err_len))
        return -1;
    if (out->tool_m == 0.0 && out->tool_radius_m > 0.0) {
        snprintf(err, err_len,
                 "arm.tool.radius_m = %g needs a length_m above 0 (a tool of "
                 "length 0 is no tool)",
                 out->tool_radius_m);
        return -1;
    }
    return 0;
}

static int parse_arm(const struct json *arm, struct qrt_arm *out, char *err,
                     size_t err_len)
{
    static const char *const keys[] = {"links_m", "link_radius_m", "limits_deg",
                                       "tool", NULL};
    const struct json *v;
    int j;
    if (arm->type != JSON_OBJECT) {
        snprintf(err, err_len, "arm must be an object");
        return -1;
    }
    if (only_keys(arm, "arm", keys, err, err_len))
        return -1;
    if ((v = json_get(arm, "links_m")) &&
        get_numbers(v, "arm.links_m", 3, 1e-6, 100.0, out->link_m, err,
                    err_len))
        return -1;
    if ((v = json_get(arm, "link_radius_m")) &&
        get_numbers(v, "arm.link_radius_m", 3, 0.0, 10.0, out->link_radius_m,
                    err, err_len))
        return -1;
    if ((v = json_get(arm, "limits_deg"))) {
        if (v->type != JSON_ARRAY || v->count != 3) {
            snprintf(err, err_len, "arm.limits_deg must be 3 [lo, hi] pairs");
            return -1;
        }
        for (j = 0; j < 3; j++) {
            char what[32];
            snprintf(what, sizeof what, "arm.limits_deg[%d]", j);
            if (get_numbers(&v->items[j], what, 2, -360.0, 360.0,
                            out->limit_deg[j], err, err_len))
                return -1;
            if (out->limit_deg[j][0] > out->limit_deg[j][1]) {
                snprintf(err, err_len, "%s: lower limit above upper", what);
                return -1;
            }
        }
        if (out->limit_deg[0][0] < -180.0 || out->limit_deg[0][1] > 180.0) {
            snprintf(err, err_len, "arm.limits_deg[0] must lie in [-180, 180]");
            return -1;
        }
    }
    if ((v = json_get(arm, "tool")) && parse_tool(v, out, err, err_len))
        return -1;
    return 0;
}

/* One field of a target's "ik": a string naming a request, "any" or one
 * side (the core's names: qrt_ik_facing_name, qrt_ik_elbow_name, values
 * 0..2); absent keeps "any". */
static int parse_ik_side(const struct json *ik, const char *what,
                         const char *key, const char *(*name_of)(int), int *out,
                         char *err, size_t err_len)
{
    const struct json *v = json_get(ik, key);
    int value;
    if (!v)
        return 0;
    if (v->type == JSON_STRING)
        for (value = 0; value <= 2; value++)
            if (strcmp(v->string, name_of(value)) == 0) {
                *out = value;
                return 0;
            }
    if (v->type == JSON_STRING)
        snprintf(err, err_len,
                 "%s.%s is \"%.64s\"; valid: \"%s\", \"%s\", \"%s\"", what, key,
                 v->string, name_of(0), name_of(1), name_of(2));
    else
        snprintf(err, err_len,
                 "%s.%s must be a string, not %s (valid: \"%s\", \"%s\", "
                 "\"%s\")",
                 what, key, json_type_name(v->type), name_of(0), name_of(1),
                 name_of(2));
    return -1;
}

static const char *facing_name(int value)
{
    return qrt_ik_facing_name((enum qrt_ik_facing)value);
}

static const char *elbow_name(int value)
{
    return qrt_ik_elbow_name((enum qrt_ik_elbow)value);
}

/* A target's "ik": the IK branches an xyz_m target may take. */
static int parse_ik(const struct json *ik, const char *key,
                    struct qrt_ik_branch *out, char *err, size_t err_len)
{
    static const char *const keys[] = {"facing", "elbow", NULL};
    char what[32];
    int facing = QRT_FACING_ANY, elbow = QRT_ELBOW_ANY;
    snprintf(what, sizeof what, "%s.ik", key);
    if (ik->type != JSON_OBJECT) {
        snprintf(err, err_len,
                 "%s must be an object with facing and/or elbow, not %s", what,
                 json_type_name(ik->type));
        return -1;
    }
    if (only_keys(ik, what, keys, err, err_len) ||
        parse_ik_side(ik, what, "facing", facing_name, &facing, err, err_len) ||
        parse_ik_side(ik, what, "elbow", elbow_name, &elbow, err, err_len))
        return -1;
    out->facing = (enum qrt_ik_facing)facing;
    out->elbow = (enum qrt_ik_elbow)elbow;
    return 0;
}

static int parse_target(const struct json *root, const char *key,
                        const struct qrt_arm *arm, struct qrt_target *t,
                        char *err, size_t err_len)
{
    static const char *const keys[] = {"joints_deg", "xyz_m", "ik", "aim",
                                       NULL};
    const struct json *v = json_get(root, key), *j, *x, *aim;
    char what[32];
    if (!v) {
        snprintf(err, err_len, "missing field \"%s\"", key);
        return -1;
    }
    if (v->type != JSON_OBJECT) {
        snprintf(err, err_len,
                 "%s must be an object with joints_deg or "
                 "xyz_m",
                 key);
        return -1;
    }
    if (only_keys(v, key, keys, err, err_len))
        return -1;
    j = json_get(v, "joints_deg");
    x = json_get(v, "xyz_m");
    if ((j != NULL) == (x != NULL)) {
        snprintf(err, err_len, "%s needs exactly one of joints_deg or xyz_m",
                 key);
        return -1;
    }
    t->ik.facing = QRT_FACING_ANY;
    t->ik.elbow = QRT_ELBOW_ANY;
    t->kind = j ? QRT_TARGET_JOINTS : QRT_TARGET_XYZ;
    if ((aim = json_get(v, "aim")) != NULL) {
        if (j) {
            snprintf(err, err_len,
                     "%s.aim applies only to xyz_m (joints_deg names one "
                     "configuration)",
                     key);
            return -1;
        }
        if (aim->type == JSON_STRING && strcmp(aim->string, "tool_tip") == 0)
            t->kind = QRT_TARGET_TOOL_TIP;
        else if (aim->type != JSON_STRING ||
                 strcmp(aim->string, "end_effector") != 0) {
            if (aim->type == JSON_STRING)
                snprintf(err, err_len,
                         "%s.aim is \"%.64s\"; valid: \"end_effector\", "
                         "\"tool_tip\"",
                         key, aim->string);
            else
                snprintf(err, err_len,
                         "%s.aim must be a string, not %s (valid: "
                         "\"end_effector\", \"tool_tip\")",
                         key, json_type_name(aim->type));
            return -1;
        }
    }
    if ((v = json_get(v, "ik")) != NULL) {
        if (j) {
            snprintf(err, err_len,
                     "%s.ik applies only to xyz_m (joints_deg names one "
                     "configuration)",
                     key);
            return -1;
        }
        if (parse_ik(v, key, &t->ik, err, err_len))
            return -1;
    }
    snprintf(what, sizeof what, "%s.%s", key, j ? "joints_deg" : "xyz_m");
    if (get_numbers(j ? j : x, what, 3, -HUGE_VAL, HUGE_VAL, t->value, err,
                    err_len))
        return -1;
    if (j && qrt_arm_check_joints(arm, t->value) != QRT_OK) {
        snprintf(err, err_len, "%s (%g, %g, %g) is outside the joint limits",
                 what, t->value[0], t->value[1], t->value[2]);
        return -1;
    }
    return 0;
}

/* Inline points on their way to the sink, a chunk at a time. */
struct inline_points {
    const struct scene_sink *sink;
    char *err;
    size_t err_len;
    long n;
    double xyz[3 * SCENE_CHUNK_POINTS];
};

static void flush_points(struct inline_points *p)
{
    if (p->n > 0 && p->sink && p->sink->add)
        p->sink->add(p->sink->ctx, p->xyz, p->n);
    p->n = 0;
}

static int take_point(void *ctx, size_t i, const struct json *item)
{
    struct inline_points *p = (struct inline_points *)ctx;
    char what[48];
    snprintf(what, sizeof what, "points[%zu]", i);
    if (get_numbers(item, what, 3, -HUGE_VAL, HUGE_VAL, p->xyz + 3 * p->n,
                    p->err, p->err_len))
        return -1;
    if (++p->n == SCENE_CHUNK_POINTS)
        flush_points(p);
    return 0;
}

/* The points array: parsed without a tree (json_parse_deferring), read
 * again here a point at a time. */
static int parse_inline_points(const char *text, size_t len,
                               const struct json *v,
                               const struct scene_sink *sink, struct scene *sc,
                               char *err, size_t err_len)
{
    struct inline_points p;
    if (v->type != JSON_ARRAY) {
        snprintf(err, err_len, "points must be an array of [x, y, z]");
        return -1;
    }
    p.sink = sink;
    p.err = err;
    p.err_len = err_len;
    p.n = 0;
    err[0] = '\0';
    if (json_each_item(text, len, v, take_point, &p, err, err_len)) {
        if (!err[0])
            snprintf(err, err_len, "out of memory");
        return -1;
    }
    flush_points(&p);
    sc->n_points += (long)v->count;
    return 0;
}

static int load_points_file(const struct json *v, const char *base_dir,
                            const struct scene_sink *sink, struct scene *sc,
                            char *err, size_t err_len)
{
    char path[4096], perr[256];
    struct pcd_source src;
    struct stat st;
    long n;
    int rc, fd, flags;
    if (v->type != JSON_STRING || v->string[0] == '\0') {
        snprintf(err, err_len, "points_file must be a file name");
        return -1;
    }
    if (v->string[0] == '/' || !base_dir || !base_dir[0])
        snprintf(path, sizeof path, "%s", v->string);
    else
        snprintf(path, sizeof path, "%s/%s", base_dir, v->string);
    /* O_NONBLOCK: a FIFO opens at once (to be refused) instead of waiting
     * for a writer; it changes nothing for a regular file */
    fd = open(path, O_RDONLY | O_NONBLOCK | O_NOCTTY);
    if (fd < 0) {
        snprintf(err, err_len, "cannot open %s: %s", path, strerror(errno));
        return -1;
    }
    if (fstat(fd, &st) != 0) {
        snprintf(err, err_len, "cannot read %s: %s", path, strerror(errno));
        close(fd);
        return -1;
    }
    if (!S_ISREG(st.st_mode)) {
        snprintf(err, err_len, "%s is %s, not a regular file", path,
                 file_kind(st.st_mode));
        close(fd);
        return -1;
    }
    if ((uint64_t)st.st_size >= SCENE_MAX_FILE_BYTES - 1) {
        close(fd);
        return too_large(path, err, err_len);
    }
    /* a regular file: blocking reads, as ever */
    flags = fcntl(fd, F_GETFL);
    if (flags >= 0)
        fcntl(fd, F_SETFL, flags & ~O_NONBLOCK);
    src.fd = fd;
    src.mem = NULL;
    src.len = (uint64_t)st.st_size;
    rc = pcd_read(&src, sink ? sink->add : NULL, sink ? sink->ctx : NULL, &n,
                  perr, sizeof perr);
    close(fd);
    if (rc) {
        snprintf(err, err_len, "%s: %s", path, perr);
        return -1;
    }
    sc->n_points += n;
    return 0;
}

int scene_parse(const char *text, size_t len, const char *base_dir,
                const struct scene_sink *sink, struct scene *sc, char *err,
                size_t err_len)
{
    static const char *const keys[] = {
        "version",  "name",     "comment",
        "arm",      "margin_m", "cspace_margin_deg",
        "grid_deg", "points",   "points_file",
        "start",    "goal",     NULL};
    const struct json *v;
    struct json *root;
    char jerr[200];
    int rc = -1;

    memset(sc, 0, sizeof *sc);
    qrt_params_default(&sc->params);
    root = json_parse_deferring(text, len, "points", jerr, sizeof jerr);
    if (!root) {
        snprintf(err, err_len, "malformed JSON %s", jerr);
        return -1;
    }
    if (root->type != JSON_OBJECT) {
        snprintf(err, err_len, "a scene must be a JSON object");
        goto out;
    }
    if (only_keys(root, "the scene", keys, err, err_len))
        goto out;
    v = json_get(root, "version");
    if (v && (v->type != JSON_NUMBER || v->number != 1.0)) {
        snprintf(err, err_len, "version must be 1");
        goto out;
    }
    if ((v = json_get(root, "arm")) &&
        parse_arm(v, &sc->params.arm, err, err_len))
        goto out;
    if (get_number(root, "margin_m", 0.0, 10.0, &sc->params.margin_m, err,
                   err_len) ||
        get_number(root, "cspace_margin_deg", 0.0, 45.0,
                   &sc->params.cspace_margin_deg, err, err_len) ||
        get_number(root, "grid_deg", QRT_GRID_DEG_MIN, 180.0,
                   &sc->params.grid_deg, err, err_len))
        goto out;
    if (sink && sink->begin)
        sink->begin(sink->ctx, &sc->params);
    if (!json_get(root, "points") && !json_get(root, "points_file")) {
        snprintf(err, err_len, "missing field \"points\" (or \"points_file\")");
        goto out;
    }
    if ((v = json_get(root, "points")) &&
        parse_inline_points(text, len, v, sink, sc, err, err_len))
        goto out;
    if ((v = json_get(root, "points_file")) &&
        load_points_file(v, base_dir, sink, sc, err, err_len))
        goto out;
    if (parse_target(root, "start", &sc->params.arm, &sc->start, err,
                     err_len) ||
        parse_target(root, "goal", &sc->params.arm, &sc->goal, err, err_len))
        goto out;
    rc = 0;
out:
    json_free(root);
    return rc;
}

int scene_load(const char *path, const struct scene_sink *sink,
               struct scene *sc, char *err, size_t err_len)
{
    char *buf, dir[4096];
    const char *slash = strrchr(path, '/');
    size_t len;
    int rc;
    memset(sc, 0, sizeof *sc);
    if (read_whole_file(path, &buf, &len, err, err_len))
        return -1;
    if (slash && (size_t)(slash - path) < sizeof dir) {
        memcpy(dir, path, (size_t)(slash - path));
        dir[slash - path] = '\0';
    } else {
        strcpy(dir, slash ? "/" : ".");
    }
    rc = scene_parse(buf, len, dir, sink, sc, err, err_len);
    budget_free(buf);
    return rc;
}
