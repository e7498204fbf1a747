/* Counting allocator for the command line's memory budget (budget.h). */
#include "budget.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* Before each block: what it was counted as, so that freeing it gives
 * back exactly that. A union so that the block after it is aligned for
 * anything. */
union block_header {
    uint64_t charged;
    long double ld;
    void *p;
    long long ll;
};

static uint64_t limit_ = UINT64_MAX, used_, peak_;
static int refused_;

void budget_init(uint64_t limit, uint64_t fixed)
{
    limit_ = limit;
    used_ = fixed;
    peak_ = fixed;
    refused_ = 0;
}

uint64_t budget_limit(void)
{
    return limit_;
}

uint64_t budget_peak(void)
{
    return peak_;
}

int budget_refused(void)
{
    return refused_;
}

/* What a block of n bytes costs: our header, and malloc's own (glibc: 8
 * bytes before the block, 16-byte granules, at least 32; blocks of 128
 * KiB and more are mapped whole pages). 0 if n is beyond any. */
static uint64_t charge_for(size_t n)
{
    uint64_t c;
    if (n > SIZE_MAX - sizeof(union block_header) - 4096)
        return 0;
    c = (uint64_t)n + sizeof(union block_header) + 8;
    c = (c + 15) & ~(uint64_t)15;
    if (c < 32)
        c = 32;
    if (c >= 128 * 1024)
        c = (c + 4095) & ~(uint64_t)4095;
    return c;
}

/* May `more` bytes be added to what is counted now? */
static int admit(uint64_t more)
{
    if (more == 0 || used_ > limit_ || more > limit_ - used_) {
        refused_ = 1;
        return 0;
    }
    return 1;
}

static void count(uint64_t at_most, uint64_t now)
{
    if (at_most > peak_)
        peak_ = at_most;
    used_ = now;
}

void *budget_malloc(size_t n)
{
    uint64_t c = charge_for(n);
    union block_header *h;
    if (!admit(c))
        return NULL;
    h = malloc(n + sizeof *h);
    if (!h)
        return NULL;
    h->charged = c;
    count(used_ + c, used_ + c);
    return h + 1;
}

void *budget_realloc(void *p, size_t n)
{
    union block_header *h, *grown;
    uint64_t c, old;
    if (!p)
        return budget_malloc(n);
    h = (union block_header *)p - 1;
    old = h->charged;
    c = charge_for(n);
    if (!admit(c)) /* the old block stays counted while it is copied */
        return NULL;
    grown = realloc(h, n + sizeof *h);
    if (!grown)
        return NULL;
    grown->charged = c;
    count(used_ + c, used_ - old + c);
    return grown + 1;
}

void budget_free(void *p)
{
    union block_header *h;
    if (!p)
        return;
    h = (union block_header *)p - 1;
    used_ -= h->charged;
    free(h);
}

int budget_parse_bytes(const char *s, uint64_t *bytes)
{
    uint64_t v = 0, unit = 1;
    const char *p = s;
    if (!(*p >= '0' && *p <= '9'))
        return -1;
    for (; *p >= '0' && *p <= '9'; p++) {
        unsigned d = (unsigned)(*p - '0');
        if (v > (UINT64_MAX - d) / 10)
            return -1;
        v = v * 10 + d;
    }
    switch (*p) {
    case 'k':
    case 'K':
        unit = (uint64_t)1 << 10;
        break;
    case 'm':
    case 'M':
        unit = (uint64_t)1 << 20;
        break;
    case 'g':
    case 'G':
        unit = (uint64_t)1 << 30;
        break;
    case 't':
    case 'T':
        unit = (uint64_t)1 << 40;
        break;
    default:
        break;
    }
    if (unit > 1) {
        p++;
        if (strcmp(p, "iB") == 0 || strcmp(p, "B") == 0)
            p += strlen(p);
    }
    if (*p || v > ((uint64_t)1 << 63) / unit)
        return -1;
    *bytes = v * unit;
    return 0;
}

void budget_format(uint64_t bytes, char *buf, size_t len)
{
    static const char *const units[] = {"KiB", "MiB", "GiB", "TiB"};
    int k = -1;
    uint64_t scale = 1;
    while (k < 3 && bytes >= scale * 1024) {
        scale *= 1024;
        k++;
    }
    if (k < 0)
        snprintf(buf, len, "%llu bytes", (unsigned long long)bytes);
    else if (bytes % scale == 0)
        snprintf(buf, len, "%llu %s", (unsigned long long)(bytes / scale),
                 units[k]);
    else
        snprintf(buf, len, "%.1f %s", (double)bytes / (double)scale, units[k]);
}
