/* libFuzzer target: the scene (JSON) and PCD readers must reject any input
 * cleanly, without crashing, leaking or reading out of bounds. */
#include <stddef.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "pcd.h"
#include "scene.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

/* The points must arrive finite, at most a chunk at a time. */
static void check_points(void *ctx, const double *xyz, long n)
{
    long i;
    (void)ctx;
    if (n < 1 || n > PCD_CHUNK_POINTS)
        abort();
    for (i = 0; i < 3 * n; i++)
        if (xyz[i] - xyz[i] != 0.0)
            abort();
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    char err[512];
    struct scene sc;
    struct scene_sink sink = {NULL, check_points, NULL};
    struct pcd_source src;
    long n = 0;
    /* copy: the readers may rely on nothing past size */
    char *buf = malloc(size ? size : 1);
    if (!buf)
        return 0;
    if (size)
        memcpy(buf, data, size);
    /* points_file names resolve inside a directory that does not exist */
    scene_parse(buf, size, "/nonexistent-qrtplan-fuzz", &sink, &sc, err,
                sizeof err);
    src.fd = -1;
    src.mem = buf;
    src.len = size;
    pcd_read(&src, check_points, NULL, &n, err, sizeof err);
    free(buf);
    return 0;
}
