/* LZF stream: a control byte c below 32 starts a literal of c + 1 bytes;
 * otherwise c's top 3 bits are a length (7: plus the next byte) and its
 * low 5 bits with the byte after the length the distance back, and
 * length + 2 bytes are copied from that far behind (they may overlap the
 * bytes being written, which repeats them). */
#include "lzf.h"

#include <string.h>

enum lzf_result lzf_decode(const unsigned char *in, size_t in_len,
                           unsigned char *out, size_t out_len)
{
    size_t ip = 0, op = 0;
    while (ip < in_len) {
        unsigned ctrl = in[ip++];
        if (ctrl < 32) {
            size_t run = (size_t)ctrl + 1;
            if (run > in_len - ip)
                return LZF_TRUNCATED;
            if (run > out_len - op)
                return LZF_TOO_LONG;
            memcpy(out + op, in + ip, run);
            ip += run;
            op += run;
        } else {
            size_t len = ctrl >> 5, back = (size_t)(ctrl & 0x1f) << 8;
            if (len == 7) {
                if (ip >= in_len)
                    return LZF_TRUNCATED;
                len += in[ip++];
            }
            if (ip >= in_len)
                return LZF_TRUNCATED;
            back += (size_t)in[ip++] + 1;
            len += 2;
            if (back > op)
                return LZF_BAD_REFERENCE;
            if (len > out_len - op)
                return LZF_TOO_LONG;
            /* byte by byte: the source may run into what is being written */
            for (; len > 0; len--, op++)
                out[op] = out[op - back];
        }
    }
    return op == out_len ? LZF_OK : LZF_TOO_SHORT;
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
    }
    return "unknown LZF result";
}
