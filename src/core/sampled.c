/* The sampled fallback (see sampled.h): RRT-Connect with proved edges. */
#include "sampled.h"

#include <math.h>

#include "motion.h"
#include "qrtplan/joints.h"
#include "tuning.h"

enum grow { TRAPPED, ADVANCED, REACHED };

/* xorshift64*: a fixed sequence from a fixed seed, uniform on [0, 1). */
static double next_uniform(uint64_t *state)
{
    uint64_t x = *state;
    x ^= x >> 12;
    x ^= x << 25;
    x ^= x >> 27;
    *state = x;
    return (double)((x * 0x2545F4914F6CDD1DULL) >> 11) *
           (1.0 / 9007199254740992.0);
}

/* q clamped into the arm's joint limits (alpha's none where it wraps):
 * a step between two configurations inside them, or a draw, may land an
 * ulp outside by rounding. */
static void clamp_to_limits(const struct qrt_sampled_space *sp, double q[3])
{
    int j;
    for (j = sp->lat->alpha_wraps ? 1 : 0; j < 3; j++) {
        if (q[j] < sp->arm->limit_deg[j][0])
            q[j] = sp->arm->limit_deg[j][0];
        if (q[j] > sp->arm->limit_deg[j][1])
            q[j] = sp->arm->limit_deg[j][1];
    }
}

/* A configuration uniform within the joint limits. */
static void random_configuration(const struct qrt_sampled_space *sp,
                                 uint64_t *state, double q[3])
{
    int j;
    for (j = 0; j < 3; j++) {
        double lo = sp->arm->limit_deg[j][0], hi = sp->arm->limit_deg[j][1];
        q[j] = lo + next_uniform(state) * (hi - lo);
    }
    clamp_to_limits(sp, q);
}

static double distance2(const struct qrt_lattice *lat, const double a[3],
                        const double b[3])
{
    double d[3];
    qrt_motion_delta(lat, a, b, d);
    return d[0] * d[0] + d[1] * d[1] + d[2] * d[2];
}

static int32_t nearest(const struct qrt_sampled_space *sp, int32_t count,
                       int32_t tree, const double q[3])
{
    int32_t i, best = -1;
    double best_d2 = 0.0;
    for (i = 0; i < count; i++)
        if (sp->node[i].tree == tree) {
            double d2 = distance2(sp->lat, sp->node[i].q_deg, q);
            if (best < 0 || d2 < best_d2) {
                best = i;
                best_d2 = d2;
            }
        }
    return best;
}

int qrt_sampled_motion_free(const struct qrt_sampled_space *sp,
                            const double a[3], const double b[3])
{
    return qrt_motion_free_exact(sp->arm, sp->radius_m, sp->pts, sp->block_box,
                                 sp->lat, a, b, QRT_EXACT_MAX_STEPS,
                                 QRT_WITNESS_AFTER);
}

/* One step of tree `tree` from its node nearest x towards x (at most
 * QRT_SAMPLED_STEP_DEG long): the new node's index in *made. */
static enum grow grow_towards(const struct qrt_sampled_space *sp,
                              int32_t *count, int32_t tree, const double x[3],
                              int32_t *made)
{
    int32_t near;
    double d[3], q[3], len;
    int j, reached = 1;
    if (*count >= sp->max_nodes)
        return TRAPPED;
    near = nearest(sp, *count, tree, x);
    qrt_motion_delta(sp->lat, sp->node[near].q_deg, x, d);
    len = sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
    for (j = 0; j < 3; j++)
        q[j] = x[j];
    if (len > QRT_SAMPLED_STEP_DEG) {
        double s = QRT_SAMPLED_STEP_DEG / len;
        reached = 0;
        for (j = 0; j < 3; j++)
            q[j] = sp->node[near].q_deg[j] + s * d[j];
        if (sp->lat->alpha_wraps)
            q[0] = qrt_wrap_deg(q[0]);
        clamp_to_limits(sp, q);
    }
    if (!qrt_sampled_motion_free(sp, sp->node[near].q_deg, q))
        return TRAPPED;
    for (j = 0; j < 3; j++)
        sp->node[*count].q_deg[j] = q[j];
    sp->node[*count].parent = near;
    sp->node[*count].tree = tree;
    *made = *count;
    ++*count;
    return reached ? REACHED : ADVANCED;
}

/* The path through the trees' meeting, start to goal, into sp->path: the
 * start tree's branch to `from_start` (root first), then the goal tree's
 * from `from_goal` (which holds the same configuration, so it is left out)
 * to its root. */
static int32_t join(const struct qrt_sampled_space *sp, int32_t from_start,
                    int32_t from_goal)
{
    int32_t n = 0, i, e;
    for (e = from_start; e >= 0; e = sp->node[e].parent)
        sp->path[n++] = e;
    for (i = 0; i < n / 2; i++) { /* root first */
        int32_t t = sp->path[i];
        sp->path[i] = sp->path[n - 1 - i];
        sp->path[n - 1 - i] = t;
    }
    for (e = sp->node[from_goal].parent; e >= 0; e = sp->node[e].parent)
        sp->path[n++] = e;
    return n;
}

int32_t qrt_sampled_connect(const struct qrt_sampled_space *sp,
                            const double qs[3], const double qg[3], long draws,
                            long *nodes_used)
{
    uint64_t state = QRT_SAMPLED_SEED;
    int32_t count = 0, tree = 0, found = 0;
    long draw;
    int j;
    *nodes_used = 0;
    if (sp->max_nodes < 2)
        return 0;
    for (j = 0; j < 3; j++) {
        sp->node[0].q_deg[j] = qs[j];
        sp->node[1].q_deg[j] = qg[j];
    }
    sp->node[0].parent = sp->node[1].parent = -1;
    sp->node[0].tree = 0;
    sp->node[1].tree = 1;
    count = 2;
    for (draw = 0; draw < draws && !found && count < sp->max_nodes; draw++) {
        double x[3];
        int32_t made = -1, other = -1;
        enum grow g;
        /* the first draw is the other end: open space needs no search */
        if (draw == 0)
            for (j = 0; j < 3; j++)
                x[j] = qg[j];
        else
            random_configuration(sp, &state, x);
        if (grow_towards(sp, &count, tree, x, &made) != TRAPPED) {
            /* the other tree reaches for the new node until it gets there
             * or is stopped (each step adds a node, so the table bounds
             * it) */
            do
                g = grow_towards(sp, &count, 1 - tree, sp->node[made].q_deg,
                                 &other);
            while (g == ADVANCED);
            if (g == REACHED)
                found =
                    tree == 0 ? join(sp, made, other) : join(sp, other, made);
        }
        tree = 1 - tree; /* the trees take turns, trapped or not */
    }
    *nodes_used = count;
    return found;
}
