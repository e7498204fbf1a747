/* Bit sets in 64-bit words (bit i is bit i & 63 of word i >> 6) and bit
 * scans on a word: the one place the core, and the tests that read its
 * tables, spell them. Internal. */
#ifndef QRT_CORE_BITS_H
#define QRT_CORE_BITS_H

#include <stdint.h>

/* Index of the lowest set bit of x (x != 0), by a de Bruijn sequence (the
 * core uses no compiler builtins). */
static inline int qrt_lowest_bit(uint64_t x)
{
    static const unsigned char at[64] = {
        0,  1,  48, 2,  57, 49, 28, 3,  61, 58, 50, 42, 38, 29, 17, 4,
        62, 55, 59, 36, 53, 51, 43, 22, 45, 39, 33, 30, 24, 18, 12, 5,
        63, 47, 56, 27, 60, 41, 37, 16, 54, 35, 52, 21, 44, 32, 23, 11,
        46, 26, 40, 15, 34, 20, 31, 10, 25, 14, 19, 9,  13, 8,  7,  6};
    return at[((x & (~x + 1U)) * 0x03F79D71B4CB0A89ULL) >> 58];
}

/* Index of the highest set bit of x (x != 0). */
static inline int qrt_highest_bit(uint64_t x)
{
    x |= x >> 1;
    x |= x >> 2;
    x |= x >> 4;
    x |= x >> 8;
    x |= x >> 16;
    x |= x >> 32;
    return qrt_lowest_bit(x ^ (x >> 1));
}

/* The bit of i within its word. */
static inline uint64_t qrt_bit_mask(long i)
{
    return 1ULL << (i & 63);
}

/* Is bit i of set set? 1 or 0. */
static inline int qrt_bit_test(const uint64_t *set, long i)
{
    return (int)((set[i >> 6] >> (i & 63)) & 1U);
}

static inline void qrt_bit_set(uint64_t *set, long i)
{
    set[i >> 6] |= qrt_bit_mask(i);
}

static inline void qrt_bit_clear(uint64_t *set, long i)
{
    set[i >> 6] &= ~qrt_bit_mask(i);
}

#endif
