#include "qrtcan/frame.h"

#include <stddef.h>

int qrtcan_node_valid(unsigned node)
{
    return node >= QRTCAN_NODE_MIN && node <= QRTCAN_NODE_MAX;
}

int qrtcan_parse_node_list(const char *text, unsigned *ids, unsigned max_ids,
                           unsigned *n_ids)
{
    unsigned n = 0, j;
    if (!text || !ids || !n_ids) {
        return QRTCAN_E_ARG;
    }
    for (;;) {
        unsigned id = 0;
        if (*text < '0' || *text > '9' || n == max_ids) {
            return QRTCAN_E_ARG;
        }
        /* stop past QRTCAN_NODE_MAX, before a long field can wrap */
        for (; *text >= '0' && *text <= '9'; text++) {
            id = id * 10u + (unsigned)(*text - '0');
            if (id > QRTCAN_NODE_MAX) {
                return QRTCAN_E_ARG;
            }
        }
        if (!qrtcan_node_valid(id) || (*text != ',' && *text != 0)) {
            return QRTCAN_E_ARG;
        }
        for (j = 0; j < n; j++) {
            if (ids[j] == id) {
                return QRTCAN_E_ARG;
            }
        }
        ids[n++] = id;
        if (*text++ == 0) {
            break;
        }
    }
    *n_ids = n;
    return QRTCAN_OK;
}

uint32_t qrtcan_cob_id(enum qrtcan_function fn, unsigned node)
{
    if (!qrtcan_node_valid(node)) {
        return 0;
    }
    return (uint32_t)fn + node;
}

int qrtcan_classify(const struct qrtcan_frame *f, enum qrtcan_kind *kind,
                    unsigned *node)
{
    uint32_t fn;
    unsigned n;
    if (f == NULL || kind == NULL || node == NULL) {
        return QRTCAN_E_ARG;
    }
    if (f->id > 0x7FFu) {
        return QRTCAN_E_ID;
    }
    if (f->dlc > 8) {
        return QRTCAN_E_DLC;
    }
    fn = f->id & 0x780u;
    n = (unsigned)(f->id & 0x7Fu);
    *node = n;
    if (f->id == 0) {
        *kind = QRTCAN_KIND_NMT;
        return QRTCAN_OK;
    }
    if (f->id == 0x080u) {
        *kind = QRTCAN_KIND_SYNC;
        *node = 0;
        return QRTCAN_OK;
    }
    if (n == 0) {
        return QRTCAN_E_ID;
    }
    switch (fn) {
    case QRTCAN_FN_SYNC_EMCY:
        *kind = QRTCAN_KIND_EMCY;
        break;
    case QRTCAN_FN_TPDO1:
        *kind = QRTCAN_KIND_TPDO1;
        break;
    case QRTCAN_FN_RPDO1:
        *kind = QRTCAN_KIND_RPDO1;
        break;
    case QRTCAN_FN_TSDO:
        *kind = QRTCAN_KIND_TSDO;
        break;
    case QRTCAN_FN_RSDO:
        *kind = QRTCAN_KIND_RSDO;
        break;
    case QRTCAN_FN_HEARTBEAT:
        *kind = QRTCAN_KIND_HEARTBEAT;
        break;
    default:
        return QRTCAN_E_ID;
    }
    return QRTCAN_OK;
}

uint16_t qrtcan_get_u16(const uint8_t *p)
{
    return (uint16_t)(p[0] | (p[1] << 8));
}

uint32_t qrtcan_get_u32(const uint8_t *p)
{
    return (uint32_t)p[0] | ((uint32_t)p[1] << 8) | ((uint32_t)p[2] << 16) |
           ((uint32_t)p[3] << 24);
}

void qrtcan_put_u16(uint8_t *p, uint16_t v)
{
    p[0] = (uint8_t)(v & 0xFFu);
    p[1] = (uint8_t)(v >> 8);
}

void qrtcan_put_u32(uint8_t *p, uint32_t v)
{
    p[0] = (uint8_t)(v & 0xFFu);
    p[1] = (uint8_t)((v >> 8) & 0xFFu);
    p[2] = (uint8_t)((v >> 16) & 0xFFu);
    p[3] = (uint8_t)(v >> 24);
}

const char *qrtcan_strerror(int err)
{
    switch (err) {
    case QRTCAN_OK:
        return "ok";
    case QRTCAN_E_ARG:
        return "bad argument";
    case QRTCAN_E_ID:
        return "unexpected COB-ID";
    case QRTCAN_E_DLC:
        return "wrong DLC";
    case QRTCAN_E_NODE:
        return "bad node id";
    case QRTCAN_E_CMD:
        return "unknown command";
    case QRTCAN_E_RANGE:
        return "value out of range";
    case QRTCAN_E_UNSUPP:
        return "unsupported transfer";
    default:
        return "unknown error";
    }
}
