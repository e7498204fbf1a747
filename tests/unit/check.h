/* Minimal test harness for the core's C unit tests: CHECK counts and
 * reports, test_done() prints the closing line and gives the exit code. */
#ifndef QRT_TEST_CHECK_H
#define QRT_TEST_CHECK_H

#include <math.h>
#include <stdio.h>
#include <stdlib.h>

static int checks_passed, checks_failed;

#define CHECK(cond, ...)                                                       \
    do {                                                                       \
        if (cond) {                                                            \
            checks_passed++;                                                   \
        } else {                                                               \
            checks_failed++;                                                   \
            fprintf(stderr, "FAIL %s:%d: %s: ", __FILE__, __LINE__, #cond);    \
            fprintf(stderr, __VA_ARGS__);                                      \
            fputc('\n', stderr);                                               \
        }                                                                      \
    } while (0)

static inline int test_done(const char *name)
{
    printf("%s: %d passed, %d failed\n", name, checks_passed, checks_failed);
    return checks_failed ? 1 : 0;
}

/* Case counts divided by QRT_TEST_SCALE (at least 1), so that emulated
 * runs (ARM under qemu, about 20 times slower) check the same things on
 * fewer cases. */
#ifndef QRT_TEST_SCALE_DEFAULT /* bare-metal builds have no environment */
#define QRT_TEST_SCALE_DEFAULT 1
#endif
static inline long test_count(long n)
{
    const char *env = getenv("QRT_TEST_SCALE");
    long scale = env ? strtol(env, NULL, 10) : QRT_TEST_SCALE_DEFAULT;
    if (scale < 1)
        scale = 1;
    return n / scale > 0 ? n / scale : 1;
}

/* Deterministic xorshift random numbers, so every run checks the same
 * cases unless QRT_SEED says otherwise. */
static unsigned long long test_rng_state = 0x9E3779B97F4A7C15ull;

static inline void test_seed(unsigned long long fallback)
{
    const char *env = getenv("QRT_SEED");
    test_rng_state = env ? strtoull(env, NULL, 10) : fallback;
    if (test_rng_state == 0)
        test_rng_state = 1;
}

static inline double test_uniform(double lo, double hi)
{
    unsigned long long x = test_rng_state;
    x ^= x << 13;
    x ^= x >> 7;
    x ^= x << 17;
    test_rng_state = x;
    return lo + (hi - lo) * (double)(x >> 11) * (1.0 / 9007199254740992.0);
}

#endif
