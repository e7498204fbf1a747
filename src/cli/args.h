/* Numbers on the command line, for the C programs (qrtplan, servo_sim): the
 * one place they are read. Each takes the whole text or nothing: no space
 * before or between (strtod and strtol would skip it), nothing after, no
 * overflow, NaN or infinity. Each returns 0 with the value(s) stored, or -1
 * with nothing promised of *out. */
#ifndef QRT_CLI_ARGS_H
#define QRT_CLI_ARGS_H

/* One number in [lo, hi]. */
int args_number(const char *s, double lo, double hi, double *out);

/* One integer in [lo, hi], in base (10; 0 also takes 0x hex and 0 octal). */
int args_long(const char *s, int base, long lo, long hi, long *out);

/* The same into an int. */
int args_int(const char *s, int base, int lo, int hi, int *out);

/* Exactly n comma-separated numbers, each in [lo, hi]. */
int args_numbers(const char *s, int n, double lo, double hi, double *out);

/* "X" for every joint or "X,Y,Z" one each, each in [lo, hi]. */
int args_per_joint(const char *s, double lo, double hi, double out[3]);

/* After --help or --version: 0, or 2 with "program: stdout: write failed"
 * on stderr when the text did not reach stdout (a script reading it must
 * not get silence and success). */
int args_finish_stdout(const char *program);

#endif
