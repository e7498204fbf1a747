#define _POSIX_C_SOURCE 200809L
/* PCD v0.7 reader: header lines, then ascii rows, packed binary rows, or
 * binary_compressed: the rows' bytes field by field (every point's x, then
 * every point's y, ...) compressed with LZF.
 *
 * The file is read a block at a time and the points go to the sink in
 * chunks, so the reader holds the same few buffers (struct pcd_buffers,
 * about 140 KiB) whatever the file holds or its header claims. For
 * binary_compressed, three LZF decoders read the one stream side by side,
 * each from its start, each skipping to the column of x, y or z: a point's
 * three coordinates come out together without the columns ever being held.
 * Every size is computed in 64 bits and checked before it is used. */
#include "pcd.h"

#include "budget.h"
#include "lzf.h"

#include <errno.h>
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/types.h>
#include <unistd.h>

#define PCD_MAX_FIELDS 32
/* WIDTH, HEIGHT and POINTS each, and WIDTH x HEIGHT */
#define PCD_MAX_POINTS 2000000000L
/* binary_compressed data expands to no more than a file may hold: this
 * bounds the work of decoding, not the memory (the data is streamed) */
#define PCD_MAX_UNCOMPRESSED_BYTES ((uint64_t)1 << 30)
/* bytes read from the file at a time; no row is longer (32 fields of 64
 * values of 8 bytes) */
#define PCD_BLOCK 16384

enum pcd_data { PCD_ASCII, PCD_BINARY, PCD_BINARY_COMPRESSED };

struct pcd_header {
    int nfields;
    char name[PCD_MAX_FIELDS][32];
    int size[PCD_MAX_FIELDS], count[PCD_MAX_FIELDS];
    char type[PCD_MAX_FIELDS];
    long width, height, points;
    enum pcd_data data;
    int seen_fields, seen_size, seen_type, seen_count;
};

/* All the reader holds, allocated once (budget_malloc). */
struct pcd_buffers {
    unsigned char block[PCD_BLOCK]; /* header, ascii text, binary rows */
    unsigned char lzf_in[3][PCD_BLOCK];
    unsigned char lzf_window[3][LZF_WINDOW];
    unsigned char column[3][PCD_CHUNK_POINTS * 8]; /* a chunk of x, y, z */
    double xyz[3 * PCD_CHUNK_POINTS];
};

/* a * b, or -1 if it passes 64 bits */
static int mul_u64(uint64_t a, uint64_t b, uint64_t *out)
{
    if (a != 0 && b > UINT64_MAX / a)
        return -1;
    *out = a * b;
    return 0;
}

/* The file, and the first thing that went wrong reading it. */
struct pcd_io {
    const struct pcd_source *src;
    int failed; /* 0, an errno, or -1: the file ended before its size */
};

/* n bytes at off (off + n within the source's size) into buf: 0, or -1
 * with io->failed set. */
static int io_read(struct pcd_io *io, uint64_t off, unsigned char *buf,
                   size_t n)
{
    const struct pcd_source *s = io->src;
    size_t got = 0;
    if (io->failed)
        return -1;
    if (!s->mem) {
        while (got < n) {
            ssize_t r = pread(s->fd, buf + got, n - got, (off_t)(off + got));
            if (r < 0 && errno == EINTR)
                continue;
            if (r <= 0) {
                io->failed = r < 0 ? errno : -1;
                return -1;
            }
            got += (size_t)r;
        }
    } else if (n > 0) {
        memcpy(buf, s->mem + off, n);
    }
    return 0;
}

/* Bytes [next, end) of the file, a block at a time. */
struct reader {
    struct pcd_io *io;
    unsigned char *buf;
    uint64_t next, end; /* file offset of the byte after buf's */
    size_t len, i;      /* buf holds len bytes, i the next unread */
};

static void reader_start(struct reader *r, struct pcd_io *io,
                         unsigned char *buf, uint64_t from, uint64_t end)
{
    r->io = io;
    r->buf = buf;
    r->next = from;
    r->end = end;
    r->len = r->i = 0;
}

/* The next byte without taking it, or -1 at the end (or a read error). */
static int peek_byte(struct reader *r)
{
    if (r->i == r->len) {
        size_t n;
        if (r->next >= r->end)
            return -1;
        n = r->end - r->next < PCD_BLOCK ? (size_t)(r->end - r->next)
                                         : PCD_BLOCK;
        if (io_read(r->io, r->next, r->buf, n))
            return -1;
        r->next += n;
        r->len = n;
        r->i = 0;
    }
    return r->buf[r->i];
}

static int get_byte(struct reader *r)
{
    int c = peek_byte(r);
    if (c >= 0)
        r->i++;
    return c;
}

/* File offset of the next byte. */
static uint64_t reader_offset(const struct reader *r)
{
    return r->next - (r->len - r->i);
}

/* Copy the next line (without its newline) into line, as much of it as
 * fits; returns 0 at end. */
static int next_line(struct reader *r, char *line, size_t cap)
{
    size_t n = 0;
    int c = get_byte(r);
    if (c < 0)
        return 0;
    while (c >= 0 && c != '\n') {
        if (n + 1 < cap)
            line[n++] = (char)c;
        c = get_byte(r);
    }
    if (n > 0 && line[n - 1] == '\r')
        n--;
    line[n] = '\0';
    return 1;
}

static int parse_ints(char *rest, int *out, int max)
{
    int n = 0;
    char *tok = strtok(rest, " \t");
    while (tok && n < max) {
        char *end;
        long v = strtol(tok, &end, 10);
        if (*end || v <= 0 || v > 64)
            return -1;
        out[n++] = (int)v;
        tok = strtok(NULL, " \t");
    }
    return tok ? -1 : n;
}

static int parse_header(struct reader *rd, struct pcd_header *h, char *err,
                        size_t err_len)
{
    char line[1024];
    memset(h, 0, sizeof *h);
    h->height = 1;
    h->points = -1;
    while (next_line(rd, line, sizeof line)) {
        char key[32], *rest;
        int i, n;
        if (line[0] == '#' || line[0] == '\0')
            continue;
        if (sscanf(line, "%31s", key) != 1)
            continue;
        rest = line + strlen(key);
        if (strcmp(key, "VERSION") == 0 || strcmp(key, "VIEWPOINT") == 0)
            continue;
        if (strcmp(key, "FIELDS") == 0) {
            char *tok = strtok(rest, " \t");
            h->nfields = 0;
            while (tok) {
                if (h->nfields == PCD_MAX_FIELDS || strlen(tok) >= 32) {
                    snprintf(err, err_len, "too many or too long FIELDS");
                    return -1;
                }
                strcpy(h->name[h->nfields++], tok);
                tok = strtok(NULL, " \t");
            }
            h->seen_fields = 1;
        } else if (strcmp(key, "SIZE") == 0) {
            n = parse_ints(rest, h->size, PCD_MAX_FIELDS);
            if (n != h->nfields) {
                snprintf(err, err_len, "SIZE does not match FIELDS");
                return -1;
            }
            h->seen_size = 1;
        } else if (strcmp(key, "COUNT") == 0) {
            n = parse_ints(rest, h->count, PCD_MAX_FIELDS);
            if (n != h->nfields) {
                snprintf(err, err_len, "COUNT does not match FIELDS");
                return -1;
            }
            h->seen_count = 1;
        } else if (strcmp(key, "TYPE") == 0) {
            char *tok = strtok(rest, " \t");
            for (i = 0; tok && i < PCD_MAX_FIELDS; i++) {
                if (strlen(tok) != 1 || !strchr("FIU", tok[0])) {
                    snprintf(err, err_len, "TYPE must be F, I or U");
                    return -1;
                }
                h->type[i] = tok[0];
                tok = strtok(NULL, " \t");
            }
            if (i != h->nfields || tok) {
                snprintf(err, err_len, "TYPE does not match FIELDS");
                return -1;
            }
            h->seen_type = 1;
        } else if (strcmp(key, "WIDTH") == 0 || strcmp(key, "HEIGHT") == 0 ||
                   strcmp(key, "POINTS") == 0) {
            char *end;
            long v;
            errno = 0;
            v = strtol(rest, &end, 10);
            while (*end == ' ' || *end == '\t')
                end++;
            if (errno || *end || v < 0 || v > PCD_MAX_POINTS) {
                snprintf(err, err_len, "bad %s value", key);
                return -1;
            }
            if (key[0] == 'W')
                h->width = v;
            else if (key[0] == 'H')
                h->height = v;
            else
                h->points = v;
        } else if (strcmp(key, "DATA") == 0) {
            char kind[32] = "";
            sscanf(rest, "%31s", kind);
            if (strcmp(kind, "ascii") == 0) {
                h->data = PCD_ASCII;
            } else if (strcmp(kind, "binary") == 0) {
                h->data = PCD_BINARY;
            } else if (strcmp(kind, "binary_compressed") == 0) {
                h->data = PCD_BINARY_COMPRESSED;
            } else {
                snprintf(err, err_len,
                         "DATA %s is not supported (ascii, binary or "
                         "binary_compressed only)",
                         kind);
                return -1;
            }
            return 0;
        } else {
            size_t i;
            for (i = 0; line[i]; i++) /* the message stays one printable line */
                if ((unsigned char)line[i] < 0x20 ||
                    (unsigned char)line[i] > 0x7e)
                    line[i] = '?';
            snprintf(err, err_len, "unknown header line '%.40s'", line);
            return -1;
        }
    }
    snprintf(err, err_len, "no DATA line: not a PCD file or truncated header");
    return -1;
}

/* Where x, y and z sit in a row: byte offset (binary) or value index
 * (ascii), and whether they are doubles. */
struct xyz_layout {
    size_t offset[3], value_index[3], row_bytes, row_values;
    int is_double[3];
};

static int layout_of(const struct pcd_header *h, struct xyz_layout *L,
                     char *err, size_t err_len)
{
    static const char *const axis[3] = {"x", "y", "z"};
    int found[3] = {0, 0, 0}, i, k;
    size_t off = 0, val = 0;
    if (!h->seen_fields || !h->seen_size || !h->seen_type) {
        snprintf(err, err_len, "header lacks FIELDS, SIZE or TYPE");
        return -1;
    }
    for (i = 0; i < h->nfields; i++) {
        int count = h->seen_count ? h->count[i] : 1;
        for (k = 0; k < 3; k++)
            if (strcmp(h->name[i], axis[k]) == 0) {
                if (h->type[i] != 'F' || (h->size[i] != 4 && h->size[i] != 8) ||
                    count != 1) {
                    snprintf(err, err_len, "field %s must be one F 4 or F 8",
                             axis[k]);
                    return -1;
                }
                found[k] = 1;
                L->offset[k] = off;
                L->value_index[k] = val;
                L->is_double[k] = h->size[i] == 8;
            }
        if (!strchr("1248", '0' + h->size[i])) {
            snprintf(err, err_len, "field size %d is not 1, 2, 4 or 8",
                     h->size[i]);
            return -1;
        }
        off += (size_t)h->size[i] * (size_t)count;
        val += (size_t)count;
    }
    if (!found[0] || !found[1] || !found[2]) {
        snprintf(err, err_len, "FIELDS must include x, y and z");
        return -1;
    }
    L->row_bytes = off;
    L->row_values = val;
    return 0;
}

static int check_point(const double *p, long i, char *err, size_t err_len)
{
    if (isfinite(p[0]) && isfinite(p[1]) && isfinite(p[2]))
        return 0;
    /* organised clouds (is_dense false) mark pixels without a return so;
     * the reader refuses them rather than guess (docs/spec.md section
     * Scene) */
    snprintf(err, err_len,
             "point %ld is not finite (NaN or Inf; a cloud that marks "
             "missing returns with NaN needs them removed first, e.g. "
             "pcl::removeNaNFromPointCloud)",
             i);
    return -1;
}

/* One coordinate as stored: a float32 or a float64, at any alignment. */
static double load_coordinate(const void *at, int is_double)
{
    if (is_double) {
        double v;
        memcpy(&v, at, sizeof v);
        return v;
    } else {
        float v;
        memcpy(&v, at, sizeof v);
        return v;
    }
}

/* Points on their way to the sink, a chunk at a time. */
struct emitter {
    pcd_sink sink;
    void *ctx;
    double *xyz; /* PCD_CHUNK_POINTS points */
    long n;
};

static void emit_flush(struct emitter *e)
{
    if (e->n > 0 && e->sink)
        e->sink(e->ctx, e->xyz, e->n);
    e->n = 0;
}

/* Check point i and pass it on: 0, or -1 with a message. */
static int emit(struct emitter *e, const double p[3], long i, char *err,
                size_t err_len)
{
    if (check_point(p, i, err, err_len))
        return -1;
    memcpy(e->xyz + 3 * e->n, p, 3 * sizeof *p);
    if (++e->n == PCD_CHUNK_POINTS)
        emit_flush(e);
    return 0;
}

static int read_binary(struct pcd_io *io, uint64_t at,
                       const struct xyz_layout *L, long n, struct emitter *e,
                       unsigned char *block, char *err, size_t err_len)
{
    uint64_t need = UINT64_MAX, avail = io->src->len - at;
    long i, rows = (long)(PCD_BLOCK / L->row_bytes);
    if (rows > PCD_CHUNK_POINTS)
        rows = PCD_CHUNK_POINTS;
    if (mul_u64(L->row_bytes, (uint64_t)n, &need) || need > avail) {
        snprintf(err, err_len,
                 "binary data truncated: %ld points need %llu "
                 "bytes, file has %llu",
                 n, (unsigned long long)need, (unsigned long long)avail);
        return -1;
    }
    for (i = 0; i < n; i += rows) {
        long m = n - i < rows ? n - i : rows, j;
        if (io_read(io, at + (uint64_t)i * L->row_bytes, block,
                    (size_t)m * L->row_bytes))
            return -1;
        for (j = 0; j < m; j++) {
            const unsigned char *row = block + (size_t)j * L->row_bytes;
            double p[3];
            int k;
            for (k = 0; k < 3; k++)
                p[k] = load_coordinate(row + L->offset[k], L->is_double[k]);
            if (emit(e, p, i + j, err, err_len))
                return -1;
        }
    }
    return 0;
}

static uint32_t le32(const unsigned char *u)
{
    return (uint32_t)u[0] | (uint32_t)u[1] << 8 | (uint32_t)u[2] << 16 |
           (uint32_t)u[3] << 24;
}

/* A decoder's input: the stream's bytes in order from the file. */
struct lzf_source {
    struct pcd_io *io;
    uint64_t next;
};

static int lzf_from_file(void *ctx, unsigned char *buf, size_t n)
{
    struct lzf_source *in = (struct lzf_source *)ctx;
    if (io_read(in->io, in->next, buf, n))
        return -1;
    in->next += n;
    return 0;
}

static int lzf_failed(enum lzf_result r, char *err, size_t err_len)
{
    snprintf(err, err_len, "binary_compressed data: %s", lzf_result_text(r));
    return -1;
}

/* Two little-endian uint32, the compressed and the uncompressed size, then
 * the LZF stream of the rows stored field by field: field f's values start
 * at n times f's offset in a row. The sizes are checked before anything is
 * decoded: a few bytes must not make the reader work through gigabytes. */
static int read_compressed(struct pcd_io *io, uint64_t at,
                           const struct xyz_layout *L, long n,
                           struct emitter *e, struct pcd_buffers *b, char *err,
                           size_t err_len)
{
    uint64_t avail = io->src->len - at, want, packed, stated;
    unsigned char sizes[8];
    struct lzf_stream dec[3];
    struct lzf_source src[3];
    enum lzf_result r;
    int k, last = 0;
    long i;
    if ((uint64_t)n > PCD_MAX_UNCOMPRESSED_BYTES / L->row_bytes) {
        snprintf(err, err_len,
                 "binary_compressed data: %ld points of %zu bytes are more "
                 "than 1 GiB",
                 n, L->row_bytes);
        return -1;
    }
    want = (uint64_t)L->row_bytes * (uint64_t)n; /* at most 1 GiB */
    if (avail < 8) {
        snprintf(err, err_len, "binary_compressed data truncated: no sizes");
        return -1;
    }
    if (io_read(io, at, sizes, sizeof sizes))
        return -1;
    packed = le32(sizes);
    stated = le32(sizes + 4);
    if (stated != want) {
        snprintf(err, err_len,
                 "binary_compressed data says %llu bytes uncompressed, but "
                 "%ld points of %zu bytes are %llu",
                 (unsigned long long)stated, n, L->row_bytes,
                 (unsigned long long)want);
        return -1;
    }
    if (packed > avail - 8) {
        snprintf(err, err_len,
                 "binary_compressed data truncated: %llu bytes stated, file "
                 "has %llu",
                 (unsigned long long)packed, (unsigned long long)(avail - 8));
        return -1;
    }
    if (want / LZF_MAX_EXPANSION > packed) {
        snprintf(err, err_len,
                 "binary_compressed data: %llu bytes cannot expand to %llu "
                 "(LZF expands at most %d times)",
                 (unsigned long long)packed, (unsigned long long)want,
                 LZF_MAX_EXPANSION);
        return -1;
    }
    for (k = 0; k < 3; k++) {
        uint64_t column;
        src[k].io = io;
        src[k].next = at + 8;
        lzf_stream_init(&dec[k], packed, want, b->lzf_in[k], PCD_BLOCK,
                        b->lzf_window[k], lzf_from_file, &src[k]);
        if (L->offset[k] > L->offset[last])
            last = k;
        if (mul_u64(L->offset[k], (uint64_t)n, &column) || column > want) {
            snprintf(err, err_len, "binary_compressed data: bad layout");
            return -1;
        }
        r = lzf_stream_read(&dec[k], NULL, column);
        if (r != LZF_OK)
            return lzf_failed(r, err, err_len);
    }
    for (i = 0; i < n; i += PCD_CHUNK_POINTS) {
        long m = n - i < PCD_CHUNK_POINTS ? n - i : PCD_CHUNK_POINTS, j;
        for (k = 0; k < 3; k++) {
            r = lzf_stream_read(&dec[k], b->column[k],
                                (uint64_t)m * (L->is_double[k] ? 8 : 4));
            if (r != LZF_OK)
                return lzf_failed(r, err, err_len);
        }
        for (j = 0; j < m; j++) {
            double p[3];
            for (k = 0; k < 3; k++)
                p[k] = load_coordinate(
                    b->column[k] + (size_t)j * (L->is_double[k] ? 8 : 4),
                    L->is_double[k]);
            if (emit(e, p, i + j, err, err_len)) {
                /* a fault in the stream comes first, wherever it is, as
                 * when the whole stream was decoded before any point */
                r = lzf_stream_finish(&dec[last]);
                return r != LZF_OK ? lzf_failed(r, err, err_len) : -1;
            }
        }
    }
    /* the decoder furthest on checks the rest of the stream */
    r = lzf_stream_finish(&dec[last]);
    return r != LZF_OK ? lzf_failed(r, err, err_len) : 0;
}

static int read_ascii(struct reader *rd, uint64_t avail,
                      const struct xyz_layout *L, long n, struct emitter *e,
                      char *err, size_t err_len)
{
    long i;
    int c;
    if ((uint64_t)n > avail) { /* a byte a point */
        snprintf(err, err_len, "ascii data truncated: POINTS %ld", n);
        return -1;
    }
    for (i = 0; i < n; i++) {
        double p[3] = {0, 0, 0};
        size_t v;
        int k;
        /* one row: row_values numbers, whitespace separated */
        for (v = 0; v < L->row_values; v++) {
            char tmp[64];
            size_t t = 0;
            double d;
            char *end;
            while ((c = peek_byte(rd)) == ' ' || c == '\t' || c == '\r' ||
                   c == '\n')
                rd->i++;
            /* a NUL ends a number too; a longer one is cut into pieces */
            while ((c = peek_byte(rd)) > 0 && !strchr(" \t\r\n", c) &&
                   t + 1 < sizeof tmp) {
                tmp[t++] = (char)c;
                rd->i++;
            }
            tmp[t] = '\0';
            if (t == 0) {
                snprintf(err, err_len,
                         "ascii data truncated at point %ld of "
                         "%ld",
                         i, n);
                return -1;
            }
            d = strtod(tmp, &end);
            if (*end) {
                snprintf(err, err_len, "bad number '%s' at point %ld", tmp, i);
                return -1;
            }
            for (k = 0; k < 3; k++)
                if (L->value_index[k] == v)
                    p[k] = d;
        }
        if (emit(e, p, i, err, err_len))
            return -1;
    }
    while ((c = peek_byte(rd)) >= 0 && strchr(" \t\r\n", c))
        rd->i++;
    if (c >= 0) {
        snprintf(err, err_len, "more data than POINTS says");
        return -1;
    }
    return 0;
}

static int read_cloud(struct pcd_io *io, struct pcd_buffers *b,
                      struct emitter *e, long *n_out, char *err, size_t err_len)
{
    struct pcd_header h;
    struct xyz_layout L = {{0}, {0}, 0, 0, {0}};
    struct reader rd;
    uint64_t at, wh;
    long n;
    int rc;
    reader_start(&rd, io, b->block, 0, io->src->len);
    if (parse_header(&rd, &h, err, err_len) || layout_of(&h, &L, err, err_len))
        return -1;
    /* each is at most PCD_MAX_POINTS: the product fits 63 bits */
    wh = (uint64_t)h.width * (uint64_t)h.height;
    if (h.points < 0) {
        if (wh > (uint64_t)PCD_MAX_POINTS) {
            snprintf(err, err_len,
                     "WIDTH x HEIGHT (%ld x %ld) is more than %ld points",
                     h.width, h.height, PCD_MAX_POINTS);
            return -1;
        }
        h.points = (long)wh;
    }
    if (wh != (uint64_t)h.points) {
        snprintf(err, err_len,
                 "WIDTH x HEIGHT (%ld x %ld) differs from "
                 "POINTS %ld",
                 h.width, h.height, h.points);
        return -1;
    }
    n = h.points;
    if (n == 0)
        return 0;
    at = reader_offset(&rd);
    if (h.data == PCD_BINARY_COMPRESSED)
        rc = read_compressed(io, at, &L, n, e, b, err, err_len);
    else if (h.data == PCD_BINARY)
        rc = read_binary(io, at, &L, n, e, b->block, err, err_len);
    else
        rc = read_ascii(&rd, io->src->len - at, &L, n, e, err, err_len);
    if (rc)
        return -1;
    emit_flush(e);
    *n_out = n;
    return 0;
}

int pcd_read(const struct pcd_source *src, pcd_sink sink, void *ctx,
             long *n_out, char *err, size_t err_len)
{
    struct pcd_io io;
    struct emitter e;
    struct pcd_buffers *b = (struct pcd_buffers *)budget_malloc(sizeof *b);
    int rc;
    *n_out = 0;
    if (!b) {
        snprintf(err, err_len, "out of memory");
        return -1;
    }
    io.src = src;
    io.failed = 0;
    e.sink = sink;
    e.ctx = ctx;
    e.xyz = b->xyz;
    e.n = 0;
    rc = read_cloud(&io, b, &e, n_out, err, err_len);
    if (io.failed) { /* what the reader made of the missing bytes is moot */
        snprintf(err, err_len, "cannot read: %s",
                 io.failed > 0 ? strerror(io.failed)
                               : "the file is shorter than when opened");
        *n_out = 0;
        rc = -1;
    }
    budget_free(b);
    return rc;
}
