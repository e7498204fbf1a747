/* LZF stream: a control byte c below 32 starts a literal of c + 1 bytes;
 * otherwise c's top 3 bits are a length (7: plus the next byte) and its
 * low 5 bits with the byte after the length the distance back, and
 * length + 2 bytes are copied from that far behind (they may overlap the
 * bytes being written, which repeats them). Each control is checked as it
 * is read, against the input left and the output still due, so that the
 * stream decoder finds the same first error as one over the whole buffer. */
#include "lzf.h"

#include <string.h>

#define WINDOW_MASK ((uint64_t)LZF_WINDOW - 1)

void lzf_stream_init(struct lzf_stream *s, uint64_t in_len, uint64_t out_len,
                     unsigned char *in_buf, size_t in_cap,
                     unsigned char *window, lzf_input input, void *ctx)
{
    memset(s, 0, sizeof *s);
    s->input = input;
    s->ctx = ctx;
    s->in = in_buf;
    s->in_cap = in_cap;
    s->in_unread = in_len;
    s->win = window;
    s->out_len = out_len;
}

static enum lzf_result fail(struct lzf_stream *s, enum lzf_result r)
{
    if (s->err == LZF_OK)
        s->err = r;
    return s->err;
}

/* Input bytes not yet decoded. */
static uint64_t in_left(const struct lzf_stream *s)
{
    return (uint64_t)(s->in_len - s->ip) + s->in_unread;
}

/* Make sure in holds an unused byte: 1, or 0 at the stream's end, or -1
 * (a read error, recorded). */
static int fill(struct lzf_stream *s)
{
    size_t n;
    if (s->ip < s->in_len)
        return 1;
    if (s->in_unread == 0)
        return 0;
    n = s->in_unread < s->in_cap ? (size_t)s->in_unread : s->in_cap;
    if (s->input(s->ctx, s->in, n) != 0) {
        fail(s, LZF_READ_ERROR);
        return -1;
    }
    s->in_len = n;
    s->ip = 0;
    s->in_unread -= n;
    return 1;
}

/* One byte of a control that needs it: 1, or 0 with the error recorded. */
static int control_byte(struct lzf_stream *s, unsigned *b)
{
    int r = fill(s);
    if (r <= 0) {
        if (r == 0)
            fail(s, LZF_TRUNCATED);
        return 0;
    }
    *b = s->in[s->ip++];
    return 1;
}

/* Read the next control and set up its run: 1, or 0 at the end of the
 * stream, or -1 with the error recorded. */
static int next_run(struct lzf_stream *s)
{
    unsigned ctrl, b;
    size_t len, back;
    int r = fill(s);
    if (r <= 0)
        return r;
    ctrl = s->in[s->ip++];
    if (ctrl < 32) {
        size_t run = (size_t)ctrl + 1;
        if (run > in_left(s)) {
            fail(s, LZF_TRUNCATED);
            return -1;
        }
        if (run > s->out_len - s->op) {
            fail(s, LZF_TOO_LONG);
            return -1;
        }
        s->lit = run;
        return 1;
    }
    len = ctrl >> 5;
    back = (size_t)(ctrl & 0x1f) << 8;
    if (len == 7) {
        if (!control_byte(s, &b))
            return -1;
        len += b;
    }
    if (!control_byte(s, &b))
        return -1;
    back += (size_t)b + 1;
    len += 2;
    if (back > s->op) {
        fail(s, LZF_BAD_REFERENCE);
        return -1;
    }
    if (len > s->out_len - s->op) {
        fail(s, LZF_TOO_LONG);
        return -1;
    }
    s->copy = len;
    s->back = back;
    return 1;
}

/* Append m bytes to the window, m at most LZF_WINDOW. */
static void put_window(struct lzf_stream *s, const unsigned char *b, size_t m)
{
    size_t dst = (size_t)(s->op & WINDOW_MASK), first = LZF_WINDOW - dst;
    if (first > m)
        first = m;
    memcpy(s->win + dst, b, first);
    memcpy(s->win, b + first, m - first);
}

enum lzf_result lzf_stream_read(struct lzf_stream *s, unsigned char *out,
                                uint64_t n)
{
    if (s->err != LZF_OK)
        return s->err;
    if (n > s->out_len - s->op)
        return LZF_TOO_SHORT;
    while (n > 0) {
        size_t m, i;
        if (s->lit == 0 && s->copy == 0) {
            int r = next_run(s);
            if (r < 0)
                return s->err;
            if (r == 0)
                return fail(s, LZF_TOO_SHORT);
        }
        if (s->lit > 0) {
            /* the run's bytes are in the stream (next_run checked) */
            if (fill(s) <= 0)
                return fail(s, LZF_READ_ERROR);
            m = s->lit;
            if (m > s->in_len - s->ip)
                m = s->in_len - s->ip;
            if (m > n)
                m = (size_t)n;
            put_window(s, s->in + s->ip, m);
            if (out) {
                memcpy(out, s->in + s->ip, m);
                out += m;
            }
            s->ip += m;
            s->lit -= m;
        } else {
            size_t dst = (size_t)(s->op & WINDOW_MASK);
            size_t src = (size_t)((s->op - s->back) & WINDOW_MASK);
            /* a piece that wraps in neither place */
            m = s->copy < n ? s->copy : (size_t)n;
            if (m > LZF_WINDOW - dst)
                m = LZF_WINDOW - dst;
            if (m > LZF_WINDOW - src)
                m = LZF_WINDOW - src;
            if (s->back >= m) {
                memmove(s->win + dst, s->win + src, m);
            } else {
                /* byte by byte: the source runs into what is being
                 * written, which repeats it */
                for (i = 0; i < m; i++)
                    s->win[dst + i] = s->win[src + i];
            }
            if (out) {
                memcpy(out, s->win + dst, m);
                out += m;
            }
            s->copy -= m;
        }
        s->op += m;
        n -= m;
    }
    return LZF_OK;
}

enum lzf_result lzf_stream_finish(struct lzf_stream *s)
{
    enum lzf_result r = lzf_stream_read(s, NULL, s->out_len - s->op);
    if (r != LZF_OK)
        return r;
    /* all out_len bytes are out: any control left holds too many */
    switch (next_run(s)) {
    case 0:
        return LZF_OK;
    case 1:
        return fail(s, LZF_TOO_LONG);
    default:
        return s->err;
    }
}

const char *lzf_result_text(enum lzf_result r)
{
    switch (r) {
    case LZF_OK:
        return "ok";
    case LZF_TRUNCATED:
        return "the compressed data ends inside a run";
    case LZF_BAD_REFERENCE:
        return "the compressed data refers back before its start";
    case LZF_TOO_LONG:
        return "the compressed data holds more than its stated size";
    case LZF_TOO_SHORT:
        return "the compressed data holds less than its stated size";
    case LZF_READ_ERROR:
        return "the compressed data cannot be read";
    }
    return "unknown LZF result";
}
