/* Reader for the Point Cloud Library's PCD files (v0.7, DATA ascii, binary
 * or binary_compressed): the x y z fields of every point, in metres. */
#ifndef QRT_CLI_PCD_H
#define QRT_CLI_PCD_H

#include <stddef.h>

/* Parse buf[0..len). On success returns 0 and a malloc'ed array of 3*n
 * doubles in *xyz (NULL when n is 0); else -1 with a message in err. Any
 * non-finite coordinate is an error. */
int pcd_parse(const char *buf, size_t len, double **xyz, long *n, char *err,
              size_t err_len);

#endif
