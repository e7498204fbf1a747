/* Scene files, version 1 (design.md section 5): the arm, margins, lattice,
 * obstacle points (inline and/or a PCD file), start and goal. */
#ifndef QRT_CLI_SCENE_H
#define QRT_CLI_SCENE_H

#include <stddef.h>

#include "qrtplan/planner.h"

struct scene {
    struct qrt_params params;
    struct qrt_target start, goal;
    double *points; /* 3 * n_points doubles, malloc'ed; inline then file */
    long n_points;
};

/* Parse a scene from text; base_dir resolves points_file. Returns 0, or -1
 * with a one-line message in err. */
int scene_parse(const char *text, size_t len, const char *base_dir,
                struct scene *sc, char *err, size_t err_len);
int scene_load(const char *path, struct scene *sc, char *err, size_t err_len);
void scene_free(struct scene *sc);

/* Whole file into a malloc'ed, NUL-terminated buffer. */
int read_whole_file(const char *path, char **buf, size_t *len, char *err,
                    size_t err_len);

#endif
