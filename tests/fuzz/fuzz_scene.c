/* libFuzzer target: the scene (JSON) and PCD readers must reject any input
 * cleanly, without crashing, leaking or reading out of bounds. */
#include <stddef.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "pcd.h"
#include "scene.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    char err[512];
    struct scene sc;
    double *xyz = NULL;
    long n = 0;
    /* copy: the readers may rely on nothing past size */
    char *buf = malloc(size ? size : 1);
    if (!buf)
        return 0;
    if (size)
        memcpy(buf, data, size);
    /* points_file names resolve inside a directory that does not exist */
    if (scene_parse(buf, size, "/nonexistent-qrtplan-fuzz", &sc, err,
                    sizeof err) == 0)
        scene_free(&sc);
    if (pcd_parse(buf, size, &xyz, &n, err, sizeof err) == 0)
        free(xyz);
    free(buf);
    return 0;
}
