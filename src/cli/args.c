/* Numbers on the command line: see args.h. */
#include "args.h"

#include <ctype.h>
#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>

/* A number at s, up to *end; -1 where strtod would skip a space or finds
 * no number, overflows, or reads NaN or infinity. */
static int number_at(const char *s, double lo, double hi, double *out,
                     char **end)
{
    double v;
    if (*s == 0 || isspace((unsigned char)*s))
        return -1;
    errno = 0;
    v = strtod(s, end);
    if (*end == s || errno != 0 || !isfinite(v) || !(v >= lo && v <= hi))
        return -1;
    *out = v;
    return 0;
}

int args_number(const char *s, double lo, double hi, double *out)
{
    return args_numbers(s, 1, lo, hi, out);
}

int args_long(const char *s, int base, long lo, long hi, long *out)
{
    char *end;
    long v;
    if (*s == 0 || isspace((unsigned char)*s))
        return -1;
    errno = 0;
    v = strtol(s, &end, base);
    if (end == s || *end != 0 || errno != 0 || v < lo || v > hi)
        return -1;
    *out = v;
    return 0;
}

int args_int(const char *s, int base, int lo, int hi, int *out)
{
    long v;
    if (args_long(s, base, lo, hi, &v) != 0)
        return -1;
    *out = (int)v;
    return 0;
}

int args_numbers(const char *s, int n, double lo, double hi, double *out)
{
    int k;
    for (k = 0; k < n; k++) {
        char *end;
        if (number_at(s, lo, hi, &out[k], &end) != 0 ||
            *end != (k + 1 < n ? ',' : 0))
            return -1;
        s = end + 1;
    }
    return 0;
}

int args_per_joint(const char *s, double lo, double hi, double out[3])
{
    int one = args_numbers(s, 1, lo, hi, out) == 0;
    if (!one && args_numbers(s, 3, lo, hi, out) != 0)
        return -1;
    if (one)
        out[1] = out[2] = out[0];
    return 0;
}

int args_finish_stdout(const char *program)
{
    if (fflush(stdout) != 0 || ferror(stdout)) {
        fprintf(stderr, "%s: stdout: write failed\n", program);
        return 2;
    }
    return 0;
}
