/* LZF decompression: the format of liblzf, which the Point Cloud Library
 * uses for PCD's DATA binary_compressed. The decoder streams: it reads its
 * input a buffer at a time and writes its output a piece at a time,
 * keeping only the last LZF_WINDOW bytes written (the farthest a back
 * reference reaches), so that its memory does not grow with the data. */
#ifndef QRT_CLI_LZF_H
#define QRT_CLI_LZF_H

#include <stddef.h>
#include <stdint.h>

enum lzf_result {
    LZF_OK = 0,
    LZF_TRUNCATED,     /* the stream ends inside a literal or a reference */
    LZF_BAD_REFERENCE, /* a back reference before the start of the output */
    LZF_TOO_LONG,      /* it decodes to more than out_len bytes */
    LZF_TOO_SHORT,     /* it ends before out_len bytes */
    LZF_READ_ERROR     /* its input could not be read */
};

/* One phrase for each result, for error messages. */
const char *lzf_result_text(enum lzf_result r);

/* Each input byte yields at most this many output bytes (a 3-byte back
 * reference copies 264), so a stated size above in_len times this is a
 * lie that need not be decoded. */
#define LZF_MAX_EXPANSION 88

/* A back reference reaches at most this far: (31 << 8) + 255 + 1. */
#define LZF_WINDOW 8192

/* The decoder's input: copies the next n bytes of the stream (n > 0, never
 * past its end) into buf; returns 0, or -1 if they cannot be read. */
typedef int (*lzf_input)(void *ctx, unsigned char *buf, size_t n);

struct lzf_stream {
    lzf_input input;
    void *ctx;
    unsigned char *in; /* in_cap bytes: the input read, from ip on unused */
    size_t in_cap, in_len, ip;
    uint64_t in_unread;  /* stream bytes not yet read into in */
    unsigned char *win;  /* LZF_WINDOW bytes: output byte k at k % LZF_WINDOW */
    uint64_t op;         /* output bytes produced */
    uint64_t out_len;    /* what the stream must decode to */
    size_t lit;          /* literal bytes of the current run still to copy */
    size_t copy, back;   /* reference bytes still to copy, from back behind */
    enum lzf_result err; /* LZF_OK until the stream fails; then it stays */
};

/* A decoder of the in_len-byte stream that input gives, which must decode
 * to out_len bytes; in_buf (in_cap > 0 bytes) and window (LZF_WINDOW bytes)
 * are the caller's. */
void lzf_stream_init(struct lzf_stream *s, uint64_t in_len, uint64_t out_len,
                     unsigned char *in_buf, size_t in_cap,
                     unsigned char *window, lzf_input input, void *ctx);

/* The next n output bytes into out, or skipped if out is NULL. LZF_OK, or
 * the first error in the stream (LZF_TOO_SHORT also if n goes past
 * out_len). */
enum lzf_result lzf_stream_read(struct lzf_stream *s, unsigned char *out,
                                uint64_t n);

/* Decode the rest: LZF_OK only if the whole stream is valid and decodes to
 * exactly out_len bytes, as a decoder of the whole buffer would say. */
enum lzf_result lzf_stream_finish(struct lzf_stream *s);

#endif
