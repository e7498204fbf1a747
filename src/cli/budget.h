/* The command line's memory budget (qrtplan plan --max-memory): a limit on
 * what the process holds at once while it reads a scene. A fixed part (the
 * planner's state, the program itself) is counted once; every buffer the
 * readers allocate goes through budget_malloc, which counts it and refuses
 * (NULL, and budget_refused() turns 1) an allocation that would pass the
 * limit, before it is made. Until budget_init is called there is no limit
 * (other programs link the readers too). Not thread-safe: the CLI reads on
 * one thread. */
#ifndef QRT_CLI_BUDGET_H
#define QRT_CLI_BUDGET_H

#include <stddef.h>
#include <stdint.h>

/* The limit in bytes, of which `fixed` is already spent. */
void budget_init(uint64_t limit, uint64_t fixed);
uint64_t budget_limit(void);
/* Most ever counted at once (the fixed part included). */
uint64_t budget_peak(void);
/* 1 once an allocation has been refused for the limit. */
int budget_refused(void);

void *budget_malloc(size_t n);
/* As realloc; while it runs, the old block and the new are both counted
 * (it may copy). */
void *budget_realloc(void *p, size_t n);
void budget_free(void *p);

/* "1073741824", "512M", "2G", "64k", "64MiB": bytes, with K, M, G or T
 * (powers of 1024, either case, optionally followed by "iB" or "B").
 * Returns 0, or -1 if s is not such a count or it passes 2^63. */
int budget_parse_bytes(const char *s, uint64_t *bytes);
/* bytes for a message: "1 GiB", "48 MiB", "1.5 GiB" or "1000 bytes". */
void budget_format(uint64_t bytes, char *buf, size_t len);

#endif
