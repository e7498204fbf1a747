/* qrtplan setpoints: see setpoints.h. */
#include "setpoints.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "json.h"
#include "plan_json.h"
#include "qrtcan/profile.h"
#include "qrtplan/joints.h"

/* a plan file is a few KB (256 waypoints at most) */
#define MAX_PLAN_BYTES ((size_t)16 << 20)

void setpoints_default(struct setpoint_options *o)
{
    struct qrtcan_master_config c;
    int j;
    qrtcan_master_config_default(&c);
    memset(o, 0, sizeof *o);
    for (j = 0; j < 3; j++) {
        o->speed_deg_s[j] = c.max_speed_deg_s[j];
        o->accel_deg_s2[j] = c.max_accel_deg_s2[j];
    }
    memcpy(o->limit_deg, c.limit_deg, sizeof o->limit_deg);
    o->period_s = (double)c.sync_period_us * 1e-6;
}

static char *read_all(const char *path, size_t *len, char *err, size_t n)
{
    FILE *f = strcmp(path, "-") == 0 ? stdin : fopen(path, "rb");
    char *buf = NULL;
    size_t used = 0, room = 0;
    if (!f) {
        snprintf(err, n, "cannot open");
        return NULL;
    }
    for (;;) {
        size_t got;
        if (used == room) {
            char *more;
            room = room ? 2 * room : 4096;
            if (room > MAX_PLAN_BYTES + 1)
                room = MAX_PLAN_BYTES + 1;
            more = used == room ? NULL : realloc(buf, room);
            if (!more) {
                snprintf(err, n,
                         used == room ? "larger than %lu MiB, not a plan"
                                      : "out of memory",
                         (unsigned long)(MAX_PLAN_BYTES >> 20));
                free(buf);
                buf = NULL;
                break;
            }
            buf = more;
        }
        got = fread(buf + used, 1, room - used, f);
        used += got;
        if (got == 0) {
            if (ferror(f)) {
                snprintf(err, n, "cannot read");
                free(buf);
                buf = NULL;
            }
            break;
        }
    }
    if (f != stdin)
        fclose(f);
    *len = used;
    return buf;
}

int setpoints_read_plan(const char *path, double (*wp)[3], int max, char *err,
                        size_t err_len)
{
    size_t len = 0, i;
    char *text = read_all(path, &len, err, err_len);
    struct json *root;
    const struct json *status, *w;
    int n = -1;
    if (!text)
        return -1;
    root = json_parse(text, len, err, err_len);
    free(text);
    if (!root)
        return -1;
    status = json_get(root, "status");
    w = json_get(root, "waypoints_deg");
    if (root->type != JSON_OBJECT || !status || status->type != JSON_STRING)
        snprintf(err, err_len, "no \"status\" string: not a plan");
    else if (strcmp(status->string, "ok") != 0)
        snprintf(err, err_len, "the plan's status is %.40s: no path",
                 status->string);
    else if (!w || w->type != JSON_ARRAY || w->count < 1 ||
             w->count > (size_t)max)
        snprintf(err, err_len,
                 "\"waypoints_deg\" must be an array of 1..%d waypoints", max);
    else {
        n = (int)w->count;
        for (i = 0; i < w->count && n >= 0; i++) {
            const struct json *p = &w->items[i];
            size_t j;
            if (p->type != JSON_ARRAY || p->count != 3) {
                snprintf(err, err_len, "waypoint %lu is not [a, s, e]",
                         (unsigned long)i);
                n = -1;
                break;
            }
            for (j = 0; j < 3; j++) {
                if (p->items[j].type != JSON_NUMBER) {
                    snprintf(err, err_len, "waypoint %lu has a non-number",
                             (unsigned long)i);
                    n = -1;
                    break;
                }
                wp[i][j] = p->items[j].number;
            }
        }
    }
    json_free(root);
    return n;
}

/* x as written: exact (the shortest decimal that reads back as x, as plan
 * files write their waypoints) for the first and the last row, so that they
 * are the plan's own numbers; the rows between to 1e-9 (seconds, degrees:
 * far below a count of any drive), trailing zeros dropped. */
static void write_number(FILE *out, double x, int exact)
{
    char buf[400];
    size_t len;
    if (exact) {
        format_exact_number(buf, x);
    } else {
        snprintf(buf, sizeof buf, "%.9f", x);
        len = strlen(buf);
        while (len > 0 && buf[len - 1] == '0')
            buf[--len] = '\0';
        if (len > 0 && buf[len - 1] == '.')
            buf[--len] = '\0';
    }
    fputs(strcmp(buf, "-0") == 0 ? "0" : buf, out);
}

static void write_row(FILE *out, double t, const double q[3], int wrap_alpha,
                      int exact)
{
    int j;
    write_number(out, t, exact);
    for (j = 0; j < 3; j++) {
        fputc(',', out);
        write_number(out, j == 0 && wrap_alpha ? qrt_wrap_deg(q[0]) : q[j],
                     exact);
    }
    fputc('\n', out);
}

int setpoints_write(FILE *out, const double (*wp)[3], int n,
                    const struct setpoint_options *o, char *err, size_t err_len)
{
    struct qrtcan_master_config cfg;
    struct qrtcan_segment seg;
    double from[3], q[3], t0 = 0.0, t;
    int i, k, bad;
    long row = 0;
    if (n < 1 || n > QRTCAN_MASTER_MAX_WAYPOINTS) {
        snprintf(err, err_len, "1..%d waypoints", QRTCAN_MASTER_MAX_WAYPOINTS);
        return -1;
    }
    if (!(o->period_s > 0.0) || !isfinite(o->period_s)) {
        snprintf(err, err_len, "the period must be positive");
        return -1;
    }
    for (i = 0; i < n; i++)
        for (k = 0; k < 3; k++)
            if (!isfinite(wp[i][k])) {
                snprintf(err, err_len, "waypoint %d is not finite", i);
                return -1;
            }
    /* the master's own check: within the limits, a non-wrapping alpha
     * stepping the short way */
    qrtcan_master_config_default(&cfg);
    memcpy(cfg.limit_deg, o->limit_deg, sizeof cfg.limit_deg);
    bad = qrtcan_path_outside_limits(&cfg, wp, n);
    if (bad >= 0) {
        snprintf(err, err_len,
                 "waypoint %d is outside the joint limits (or alpha steps "
                 "the long way round where it does not wrap): the master "
                 "would refuse the path",
                 bad);
        return -1;
    }
    memcpy(from, wp[0], sizeof from);
    fputs("t_s,alpha_deg,sigma_deg,eta_deg\n", out);
    /* segment i takes the joints from `from` (alpha continuous) to wp[i];
     * rows at row * period_s, each in the segment whose time holds it */
    for (i = 1; i < n; i++) {
        double step[3];
        qrtcan_segment_step(from, wp[i], step);
        if (qrtcan_segment_profile(o->speed_deg_s, o->accel_deg_s2, step,
                                   &seg) != QRTCAN_OK) {
            snprintf(err, err_len,
                     "speeds and accelerations must be "
                     "positive and finite");
            return -1;
        }
        while ((t = (double)row * o->period_s) < t0 + seg.duration_s) {
            qrtcan_segment_at(&seg, from, t - t0, q, NULL);
            write_row(out, t, q, o->wrap_alpha, row == 0);
            row++;
        }
        for (k = 0; k < 3; k++)
            from[k] += step[k];
        /* sigma and eta land on the waypoint's own numbers */
        from[1] = wp[i][1];
        from[2] = wp[i][2];
        t0 += seg.duration_s;
    }
    /* the end: the last waypoint, at the path's whole duration */
    write_row(out, t0, from, o->wrap_alpha, 1);
    return 0;
}
