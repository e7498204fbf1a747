#include "qrtcan/sdo.h"

#include <stddef.h>
#include <string.h>

/* Command specifiers: bits 7..5 of byte 0. */
#define CS(b) ((unsigned)(b) >> 5)
#define CCS_DOWNLOAD_SEGMENT 0u
#define CCS_DOWNLOAD 1u
#define CCS_UPLOAD 2u
#define CCS_UPLOAD_SEGMENT 3u
#define CS_ABORT 4u
#define SCS_UPLOAD 2u
#define SCS_DOWNLOAD 3u
/* Expedited (e) and size indicated (s) bits, and n: bytes that hold no
 * data, in bits 3..2, valid when e and s are both set. */
#define BIT_E 0x02u
#define BIT_S 0x01u

static void put_mux(struct qrtcan_frame *f, const struct qrtcan_sdo *s)
{
    qrtcan_put_u16(&f->data[1], s->index);
    f->data[3] = s->subindex;
}

static void get_mux(const struct qrtcan_frame *f, struct qrtcan_sdo *s)
{
    s->index = qrtcan_get_u16(&f->data[1]);
    s->subindex = f->data[3];
    s->size = 0;
    s->data = 0;
}

/* The low 1, 2 or 3 bytes of a 32-bit value, by size (a table: a shift by
 * 8 * size would need its range proved to every checker). */
static const uint32_t low_bytes[4] = {0xFFFFFFFFu, 0x000000FFu, 0x0000FFFFu,
                                      0x00FFFFFFu};

/* The value's bytes as the frame carries them: only `size` of them count. */
static uint32_t masked(uint32_t v, unsigned size)
{
    return size == 0 || size >= 4 ? v : v & low_bytes[size];
}

static int expedited_byte(unsigned cs, unsigned size, uint8_t *b)
{
    if (size > 4) {
        return QRTCAN_E_ARG;
    }
    if (size == 0) {
        *b = (uint8_t)((cs << 5) | BIT_E);
    } else {
        *b = (uint8_t)((cs << 5) | ((4u - size) << 2) | BIT_E | BIT_S);
    }
    return QRTCAN_OK;
}

/* Size and data of an expedited initiate frame; QRTCAN_E_UNSUPP when the
 * frame starts a segmented transfer instead. */
static int expedited_data(const struct qrtcan_frame *f, struct qrtcan_sdo *s)
{
    unsigned b = f->data[0];
    if ((b & BIT_E) == 0) {
        return QRTCAN_E_UNSUPP;
    }
    s->size = (b & BIT_S) ? (uint8_t)(4u - ((b >> 2) & 3u)) : 0;
    s->data = masked(qrtcan_get_u32(&f->data[4]), s->size);
    return QRTCAN_OK;
}

static int encode(uint32_t id, const struct qrtcan_sdo *s,
                  struct qrtcan_frame *f, int client)
{
    int rc;
    memset(f, 0, sizeof *f);
    f->id = id;
    f->dlc = 8;
    put_mux(f, s);
    switch (s->type) {
    case QRTCAN_SDO_READ:
        if (!client) {
            return QRTCAN_E_ARG;
        }
        f->data[0] = (uint8_t)(CCS_UPLOAD << 5);
        return QRTCAN_OK;
    case QRTCAN_SDO_WRITE:
        if (!client) {
            return QRTCAN_E_ARG;
        }
        rc = expedited_byte(CCS_DOWNLOAD, s->size, &f->data[0]);
        break;
    case QRTCAN_SDO_READ_OK:
        if (client) {
            return QRTCAN_E_ARG;
        }
        rc = expedited_byte(SCS_UPLOAD, s->size, &f->data[0]);
        break;
    case QRTCAN_SDO_WRITE_OK:
        if (client) {
            return QRTCAN_E_ARG;
        }
        f->data[0] = (uint8_t)(SCS_DOWNLOAD << 5);
        return QRTCAN_OK;
    case QRTCAN_SDO_ABORT:
        f->data[0] = (uint8_t)(CS_ABORT << 5);
        qrtcan_put_u32(&f->data[4], s->data);
        return QRTCAN_OK;
    default:
        return QRTCAN_E_ARG;
    }
    if (rc == QRTCAN_OK) {
        qrtcan_put_u32(&f->data[4], masked(s->data, s->size));
    }
    return rc;
}

static int check_frame(const struct qrtcan_frame *f, uint32_t base,
                       unsigned *node)
{
    if (f->id <= base || f->id > base + QRTCAN_NODE_MAX) {
        return QRTCAN_E_ID;
    }
    /* CiA 301 fixes SDO frames at eight bytes. */
    if (f->dlc != 8) {
        return QRTCAN_E_DLC;
    }
    *node = (unsigned)(f->id - base);
    return QRTCAN_OK;
}

int qrtcan_sdo_encode_request(unsigned node, const struct qrtcan_sdo *s,
                              struct qrtcan_frame *f)
{
    if (s == NULL || f == NULL) {
        return QRTCAN_E_ARG;
    }
    if (!qrtcan_node_valid(node)) {
        return QRTCAN_E_NODE;
    }
    return encode(qrtcan_cob_id(QRTCAN_FN_RSDO, node), s, f, 1);
}

int qrtcan_sdo_encode_response(unsigned node, const struct qrtcan_sdo *s,
                               struct qrtcan_frame *f)
{
    if (s == NULL || f == NULL) {
        return QRTCAN_E_ARG;
    }
    if (!qrtcan_node_valid(node)) {
        return QRTCAN_E_NODE;
    }
    return encode(qrtcan_cob_id(QRTCAN_FN_TSDO, node), s, f, 0);
}

int qrtcan_sdo_decode_request(const struct qrtcan_frame *f, unsigned *node,
                              struct qrtcan_sdo *s)
{
    int rc;
    if (f == NULL || node == NULL || s == NULL) {
        return QRTCAN_E_ARG;
    }
    rc = check_frame(f, QRTCAN_FN_RSDO, node);
    if (rc != QRTCAN_OK) {
        return rc;
    }
    get_mux(f, s);
    switch (CS(f->data[0])) {
    case CCS_UPLOAD:
        s->type = QRTCAN_SDO_READ;
        return QRTCAN_OK;
    case CCS_DOWNLOAD:
        s->type = QRTCAN_SDO_WRITE;
        return expedited_data(f, s);
    case CS_ABORT:
        s->type = QRTCAN_SDO_ABORT;
        s->data = qrtcan_get_u32(&f->data[4]);
        return QRTCAN_OK;
    case CCS_DOWNLOAD_SEGMENT:
    case CCS_UPLOAD_SEGMENT:
        /* segments carry no multiplexer: there is no object to name */
        s->index = 0;
        s->subindex = 0;
        return QRTCAN_E_UNSUPP;
    default: /* 5, 6: block transfers; 7: reserved */
        return (CS(f->data[0]) == 7u) ? QRTCAN_E_CMD : QRTCAN_E_UNSUPP;
    }
}

int qrtcan_sdo_decode_response(const struct qrtcan_frame *f, unsigned *node,
                               struct qrtcan_sdo *s)
{
    int rc;
    if (f == NULL || node == NULL || s == NULL) {
        return QRTCAN_E_ARG;
    }
    rc = check_frame(f, QRTCAN_FN_TSDO, node);
    if (rc != QRTCAN_OK) {
        return rc;
    }
    get_mux(f, s);
    switch (CS(f->data[0])) {
    case SCS_UPLOAD:
        s->type = QRTCAN_SDO_READ_OK;
        return expedited_data(f, s);
    case SCS_DOWNLOAD:
        s->type = QRTCAN_SDO_WRITE_OK;
        return QRTCAN_OK;
    case CS_ABORT:
        s->type = QRTCAN_SDO_ABORT;
        s->data = qrtcan_get_u32(&f->data[4]);
        return QRTCAN_OK;
    case 0u: /* upload segment */
    case 1u: /* download segment ack */
    case 5u:
    case 6u:
        return QRTCAN_E_UNSUPP;
    default:
        return QRTCAN_E_CMD;
    }
}

int32_t qrtcan_sdo_signed(const struct qrtcan_sdo *s)
{
    unsigned size;
    uint32_t v, sign;
    if (s == NULL) {
        return 0;
    }
    size = s->size == 0 ? 4u : s->size;
    v = masked(s->data, size);
    if (size < 4) {
        sign = (low_bytes[size] >> 1) + 1u; /* the top bit of the low bytes */
        if (v & sign) {
            v |= ~low_bytes[size];
        }
    }
    /* two's complement bit pattern into int32 without implementation-
     * defined conversion */
    return (v & 0x80000000u) ? -(int32_t)(~v) - 1 : (int32_t)v;
}
