/* CAN frames and CANopen COB-IDs: the common ground of every qrtcan codec.
 *
 * Portable C99: no OS calls, no malloc, no stdio. Every decoder checks the
 * identifier and the DLC before it reads a byte and returns a negative
 * qrtcan_err on anything it does not recognise, so a frame straight off the
 * bus (garbage included) can be handed to any decoder.
 */
#ifndef QRTCAN_FRAME_H
#define QRTCAN_FRAME_H

#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

/* Classic CAN, 11-bit identifiers (CANopen's predefined connection set). */
struct qrtcan_frame {
    uint32_t id; /* 0..0x7FF; anything larger is refused by the decoders */
    uint8_t dlc; /* 0..8 */
    uint8_t data[8];
};

enum qrtcan_err {
    QRTCAN_OK = 0,
    QRTCAN_E_ARG = -1,    /* NULL pointer or argument out of range */
    QRTCAN_E_ID = -2,     /* not the COB-ID this decoder handles */
    QRTCAN_E_DLC = -3,    /* wrong data length for this frame */
    QRTCAN_E_NODE = -4,   /* node id outside 1..127, or not the one asked */
    QRTCAN_E_CMD = -5,    /* unknown command / command specifier */
    QRTCAN_E_RANGE = -6,  /* value does not fit (e.g. degrees -> counts) */
    QRTCAN_E_UNSUPP = -7, /* valid CANopen, but not supported (segmented SDO) */
};

/* Function codes of the predefined connection set (CiA 301 7.3.5): the
 * upper four bits of the 11-bit identifier. */
enum qrtcan_function {
    QRTCAN_FN_NMT = 0x000,
    QRTCAN_FN_SYNC_EMCY = 0x080, /* 0x080 SYNC, 0x080 + node EMCY */
    QRTCAN_FN_TPDO1 = 0x180,
    QRTCAN_FN_RPDO1 = 0x200,
    QRTCAN_FN_TSDO = 0x580, /* server (drive) -> client */
    QRTCAN_FN_RSDO = 0x600, /* client -> server (drive) */
    QRTCAN_FN_HEARTBEAT = 0x700,
};

#define QRTCAN_NODE_MIN 1
#define QRTCAN_NODE_MAX 127

/* What kind of frame this is, by identifier and DLC alone. */
enum qrtcan_kind {
    QRTCAN_KIND_NMT,
    QRTCAN_KIND_SYNC,
    QRTCAN_KIND_EMCY,
    QRTCAN_KIND_TPDO1,
    QRTCAN_KIND_RPDO1,
    QRTCAN_KIND_TSDO,
    QRTCAN_KIND_RSDO,
    QRTCAN_KIND_HEARTBEAT,
};

/* 1 if node is a valid CANopen node id (1..127). */
int qrtcan_node_valid(unsigned node);

/* Reads "A,B,..." into ids[0..*n_ids): 1..max_ids distinct node ids, each
 * field decimal digits only (no sign, space or prefix) of a valid node.
 * QRTCAN_OK, or QRTCAN_E_ARG for anything else, among them an empty field
 * ("1,,3", "1,2,"), with *n_ids untouched (ids may be partly written). For
 * command lines and configs: a mistyped id must not wrap onto another drive's.
 */
int qrtcan_parse_node_list(const char *text, unsigned *ids, unsigned max_ids,
                           unsigned *n_ids);

/* The COB-ID of function fn for node (fn + node), or 0 with an invalid node. */
uint32_t qrtcan_cob_id(enum qrtcan_function fn, unsigned node);

/* Sorts a frame into *kind and *node (0 for NMT and SYNC). QRTCAN_E_ID for
 * identifiers outside the connection set this project uses, QRTCAN_E_DLC
 * for a DLC above 8. */
int qrtcan_classify(const struct qrtcan_frame *f, enum qrtcan_kind *kind,
                    unsigned *node);

/* Little-endian field access (CANopen is little-endian on the wire). */
uint16_t qrtcan_get_u16(const uint8_t *p);
uint32_t qrtcan_get_u32(const uint8_t *p);
void qrtcan_put_u16(uint8_t *p, uint16_t v);
void qrtcan_put_u32(uint8_t *p, uint32_t v);

/* A short, constant English name of an error code (for log lines). */
const char *qrtcan_strerror(int err);

#ifdef __cplusplus
}
#endif

#endif
