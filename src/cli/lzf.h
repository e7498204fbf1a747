/* LZF decompression: the format of liblzf, which the Point Cloud Library
 * uses for PCD's DATA binary_compressed. */
#ifndef QRT_CLI_LZF_H
#define QRT_CLI_LZF_H

#include <stddef.h>

enum lzf_result {
    LZF_OK = 0,
    LZF_TRUNCATED,     /* the stream ends inside a literal or a reference */
    LZF_BAD_REFERENCE, /* a back reference before the start of the output */
    LZF_TOO_LONG,      /* it decodes to more than out_len bytes */
    LZF_TOO_SHORT      /* it ends before out_len bytes */
};

/* Decode in[0..in_len) into out[0..out_len): LZF_OK only if the stream
 * fills out exactly. Never reads or writes outside the two buffers. */
enum lzf_result lzf_decode(const unsigned char *in, size_t in_len,
                           unsigned char *out, size_t out_len);

/* One phrase for each result, for error messages. */
const char *lzf_result_text(enum lzf_result r);

/* Each input byte yields at most this many output bytes (a 3-byte back
 * reference copies 264), so a stated size above in_len times this is a
 * lie that need not be allocated. */
#define LZF_MAX_EXPANSION 88

#endif
