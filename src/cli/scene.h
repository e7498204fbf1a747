/* Scene files, version 1 (docs/spec.md section Scene): the arm, margins,
 * lattice, obstacle points (inline and/or a PCD file), start and goal. */
#ifndef QRT_CLI_SCENE_H
#define QRT_CLI_SCENE_H

#include <stddef.h>

#include "qrtplan/planner.h"

struct scene {
    struct qrt_params params;
    struct qrt_target start, goal;
    long n_points; /* given to the sink: inline, then the file's */
};

/* Where a scene's points go as they are read, never held whole: begin
 * once the arm, margins and lattice are read (before any point, and
 * always before a scene is accepted), then add with the points in order,
 * inline first, in chunks of at most SCENE_CHUNK_POINTS. Either may be
 * NULL. */
#define SCENE_CHUNK_POINTS 1024
struct scene_sink {
    void (*begin)(void *ctx, const struct qrt_params *params);
    void (*add)(void *ctx, const double *xyz, long n);
    void *ctx;
};

/* Parse a scene from text; base_dir resolves points_file; sink (may be
 * NULL) gets its points. Returns 0, or -1 with a one-line message in err
 * (the sink may have had points by then). Memory: the JSON tree of all but
 * the points, one point's tree, and the PCD reader's fixed buffers, every
 * byte counted against the budget (budget.h). */
int scene_parse(const char *text, size_t len, const char *base_dir,
                const struct scene_sink *sink, struct scene *sc, char *err,
                size_t err_len);
/* The same from a file ("-": standard input), held whole while it is
 * parsed: a regular file, a pipe or a terminal, at most 1 GiB. */
int scene_load(const char *path, const struct scene_sink *sink,
               struct scene *sc, char *err, size_t err_len);

/* Whole file into a budget_malloc'ed, NUL-terminated buffer (free it with
 * budget_free). */
int read_whole_file(const char *path, char **buf, size_t *len, char *err,
                    size_t err_len);

#endif
