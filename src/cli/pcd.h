/* Reader for the Point Cloud Library's PCD files (v0.7, DATA ascii, binary
 * or binary_compressed): the x y z fields of every point, in metres. It
 * reads the file a block at a time and hands the points on in chunks, in
 * the file's order: its memory is the same ~140 KiB (one budget_malloc)
 * whatever the file holds or its header claims. */
#ifndef QRT_CLI_PCD_H
#define QRT_CLI_PCD_H

#include <stddef.h>
#include <stdint.h>

/* Where the file's bytes are: an open file read with pread (mem NULL), or
 * memory; len bytes either way. */
struct pcd_source {
    int fd;
    const char *mem;
    uint64_t len;
};

/* Points go to the sink this many at a time at most. */
#define PCD_CHUNK_POINTS 1024

/* n points, 3n doubles (x, y, z), every coordinate finite. */
typedef void (*pcd_sink)(void *ctx, const double *xyz, long n);

/* Read every point into sink (NULL: only check them). Returns 0 with the
 * count in *n, or -1 with a one-line message in err; the sink may have had
 * some of the points by then. Any non-finite coordinate is an error. */
int pcd_read(const struct pcd_source *src, pcd_sink sink, void *ctx, long *n,
             char *err, size_t err_len);

#endif
