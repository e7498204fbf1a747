#define _POSIX_C_SOURCE 200809L
/* PCD v0.7 reader: header lines, then ascii rows, packed binary rows, or
 * binary_compressed: the rows' bytes field by field (every point's x, then
 * every point's y, ...) compressed with LZF. */
#include "pcd.h"

#include "lzf.h"

#include <errno.h>
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define PCD_MAX_FIELDS 32
/* binary_compressed data expands to no more than a file may hold */
#define PCD_MAX_UNCOMPRESSED_BYTES (1ul << 30)

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

/* Copy the next line (without its newline) into line; returns 0 at end. */
static int next_line(const char *buf, size_t len, size_t *pos, char *line,
                     size_t cap)
{
    size_t n = 0;
    if (*pos >= len)
        return 0;
    while (*pos < len && buf[*pos] != '\n') {
        if (n + 1 < cap)
            line[n++] = buf[*pos];
        (*pos)++;
    }
    if (*pos < len)
        (*pos)++;
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

static int parse_header(const char *buf, size_t len, size_t *pos,
                        struct pcd_header *h, char *err, size_t err_len)
{
    char line[1024];
    memset(h, 0, sizeof *h);
    h->height = 1;
    h->points = -1;
    while (next_line(buf, len, pos, line, sizeof line)) {
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
            if (errno || *end || v < 0 || v > 2000000000L) {
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
     * design.md has the reader refuse them rather than guess */
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

static int read_binary(const char *data, size_t avail,
                       const struct xyz_layout *L, long n, double *xyz,
                       char *err, size_t err_len)
{
    long i;
    int k;
    if (L->row_bytes == 0 || avail / L->row_bytes < (size_t)n) {
        snprintf(err, err_len,
                 "binary data truncated: %ld points need %zu "
                 "bytes, file has %zu",
                 n, (size_t)n * L->row_bytes, avail);
        return -1;
    }
    for (i = 0; i < n; i++) {
        const char *row = data + (size_t)i * L->row_bytes;
        for (k = 0; k < 3; k++)
            xyz[3 * i + k] =
                load_coordinate(row + L->offset[k], L->is_double[k]);
        if (check_point(xyz + 3 * i, i, err, err_len))
            return -1;
    }
    return 0;
}

static uint32_t le32(const char *p)
{
    const unsigned char *u = (const unsigned char *)p;
    return (uint32_t)u[0] | (uint32_t)u[1] << 8 | (uint32_t)u[2] << 16 |
           (uint32_t)u[3] << 24;
}

/* Two little-endian uint32, the compressed and the uncompressed size, then
 * the LZF stream. Checked before anything is allocated: a few bytes must
 * not make the reader ask for gigabytes. */
static int check_compressed_sizes(const char *data, size_t avail,
                                  const struct xyz_layout *L, long n, char *err,
                                  size_t err_len)
{
    size_t want, packed, stated;
    if ((size_t)n > PCD_MAX_UNCOMPRESSED_BYTES / L->row_bytes) {
        snprintf(err, err_len,
                 "binary_compressed data: %ld points of %zu bytes are more "
                 "than 1 GiB",
                 n, L->row_bytes);
        return -1;
    }
    want = L->row_bytes * (size_t)n;
    if (avail < 8) {
        snprintf(err, err_len, "binary_compressed data truncated: no sizes");
        return -1;
    }
    packed = le32(data);
    stated = le32(data + 4);
    if (stated != want) {
        snprintf(err, err_len,
                 "binary_compressed data says %zu bytes uncompressed, but "
                 "%ld points of %zu bytes are %zu",
                 stated, n, L->row_bytes, want);
        return -1;
    }
    if (packed > avail - 8) {
        snprintf(err, err_len,
                 "binary_compressed data truncated: %zu bytes stated, file "
                 "has %zu",
                 packed, avail - 8);
        return -1;
    }
    if (want / LZF_MAX_EXPANSION > packed) {
        snprintf(err, err_len,
                 "binary_compressed data: %zu bytes cannot expand to %zu "
                 "(LZF expands at most %d times)",
                 packed, want, LZF_MAX_EXPANSION);
        return -1;
    }
    return 0;
}

/* The rows stored field by field (every point's x, then every point's y,
 * ...): field f's values start at n times f's offset in a row. Sizes as
 * check_compressed_sizes passed them. */
static int read_compressed(const char *data, const struct xyz_layout *L, long n,
                           double *xyz, char *err, size_t err_len)
{
    size_t want = L->row_bytes * (size_t)n, packed = le32(data);
    unsigned char *raw;
    enum lzf_result r;
    long i;
    int k;
    raw = malloc(want);
    if (!raw) {
        snprintf(err, err_len, "out of memory for %zu bytes", want);
        return -1;
    }
    r = lzf_decode((const unsigned char *)data + 8, packed, raw, want);
    if (r != LZF_OK) {
        snprintf(err, err_len, "binary_compressed data: %s",
                 lzf_result_text(r));
        free(raw);
        return -1;
    }
    for (i = 0; i < n; i++) {
        for (k = 0; k < 3; k++) {
            size_t width = L->is_double[k] ? 8 : 4;
            xyz[3 * i + k] = load_coordinate(raw + L->offset[k] * (size_t)n +
                                                 (size_t)i * width,
                                             L->is_double[k]);
        }
        if (check_point(xyz + 3 * i, i, err, err_len)) {
            free(raw);
            return -1;
        }
    }
    free(raw);
    return 0;
}

static int read_ascii(const char *buf, size_t len, size_t pos,
                      const struct xyz_layout *L, long n, double *xyz,
                      char *err, size_t err_len)
{
    long i;
    for (i = 0; i < n; i++) {
        size_t v;
        int k;
        /* one row: row_values numbers, whitespace separated */
        for (v = 0; v < L->row_values; v++) {
            char tmp[64];
            size_t t = 0;
            double d;
            char *end;
            while (pos < len && (buf[pos] == ' ' || buf[pos] == '\t' ||
                                 buf[pos] == '\r' || buf[pos] == '\n'))
                pos++;
            while (pos < len && !strchr(" \t\r\n", buf[pos]) &&
                   t + 1 < sizeof tmp)
                tmp[t++] = buf[pos++];
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
                    xyz[3 * i + k] = d;
        }
        if (check_point(xyz + 3 * i, i, err, err_len))
            return -1;
    }
    while (pos < len && strchr(" \t\r\n", buf[pos]))
        pos++;
    if (pos < len) {
        snprintf(err, err_len, "more data than POINTS says");
        return -1;
    }
    return 0;
}

int pcd_parse(const char *buf, size_t len, double **xyz_out, long *n_out,
              char *err, size_t err_len)
{
    struct pcd_header h;
    struct xyz_layout L = {{0}, {0}, 0, 0, {0}};
    size_t pos = 0;
    double *xyz;
    long n;
    *xyz_out = NULL;
    *n_out = 0;
    if (parse_header(buf, len, &pos, &h, err, err_len) ||
        layout_of(&h, &L, err, err_len))
        return -1;
    if (h.points < 0)
        h.points = h.width * h.height;
    if (h.width * h.height != h.points) {
        snprintf(err, err_len,
                 "WIDTH x HEIGHT (%ld x %ld) differs from "
                 "POINTS %ld",
                 h.width, h.height, h.points);
        return -1;
    }
    n = h.points;
    if (n == 0)
        return 0;
    if (h.data == PCD_BINARY && L.row_bytes * (size_t)n > len - pos) {
        snprintf(err, err_len,
                 "binary data truncated: %ld points need %zu "
                 "bytes, file has %zu",
                 n, (size_t)n * L.row_bytes, len - pos);
        return -1;
    }
    if (h.data == PCD_ASCII && (size_t)n > len - pos) { /* a byte a point */
        snprintf(err, err_len, "ascii data truncated: POINTS %ld", n);
        return -1;
    }
    if (h.data == PCD_BINARY_COMPRESSED &&
        check_compressed_sizes(buf + pos, len - pos, &L, n, err, err_len))
        return -1;
    xyz = malloc((size_t)n * 3 * sizeof *xyz);
    if (!xyz) {
        snprintf(err, err_len, "out of memory for %ld points", n);
        return -1;
    }
    if (h.data == PCD_BINARY_COMPRESSED
            ? read_compressed(buf + pos, &L, n, xyz, err, err_len)
        : h.data == PCD_BINARY
            ? read_binary(buf + pos, len - pos, &L, n, xyz, err, err_len)
            : read_ascii(buf, len, pos, &L, n, xyz, err, err_len)) {
        free(xyz);
        return -1;
    }
    *xyz_out = xyz;
    *n_out = n;
    return 0;
}
