/* Expedited SDO (CiA 301 7.2.4.3): reads and writes of object dictionary
 * entries of up to four bytes, one request frame and one answer frame.
 * Client side (the master): encode requests, decode answers. Server side
 * (a drive): decode requests, encode answers.
 *
 * Segmented and block transfers are not supported: their requests decode
 * to QRTCAN_E_UNSUPP with index and subindex filled in, so a server can
 * abort them with QRTCAN_SDO_ABORT_CMD naming the right object.
 */
#ifndef QRTCAN_SDO_H
#define QRTCAN_SDO_H

#include "qrtcan/frame.h"

#ifdef __cplusplus
extern "C" {
#endif

enum qrtcan_sdo_type {
    QRTCAN_SDO_READ,     /* client: initiate upload request */
    QRTCAN_SDO_WRITE,    /* client: initiate download request, expedited */
    QRTCAN_SDO_READ_OK,  /* server: expedited upload response with data */
    QRTCAN_SDO_WRITE_OK, /* server: download response */
    QRTCAN_SDO_ABORT,    /* either side: abort, data = abort code */
};

struct qrtcan_sdo {
    enum qrtcan_sdo_type type;
    uint16_t index;
    uint8_t subindex;
    /* bytes of data for READ_OK and WRITE: 1..4, or 0 when the frame does
     * not indicate the size (then all four bytes are data). */
    uint8_t size;
    uint32_t data; /* the value (little-endian on the wire), or abort code */
};

/* Abort codes (CiA 301 table 22). */
#define QRTCAN_SDO_ABORT_TIMEOUT 0x05040000u
#define QRTCAN_SDO_ABORT_CMD 0x05040001u    /* command specifier invalid */
#define QRTCAN_SDO_ABORT_ACCESS 0x06010000u /* unsupported access */
#define QRTCAN_SDO_ABORT_WRITE_ONLY 0x06010001u
#define QRTCAN_SDO_ABORT_READ_ONLY 0x06010002u
#define QRTCAN_SDO_ABORT_NO_OBJECT 0x06020000u
/* general parameter incompatibility */
#define QRTCAN_SDO_ABORT_INCOMPATIBLE 0x06040043u
#define QRTCAN_SDO_ABORT_LENGTH 0x06070010u /* data type length mismatch */
#define QRTCAN_SDO_ABORT_NO_SUBINDEX 0x06090011u
#define QRTCAN_SDO_ABORT_VALUE 0x06090030u /* value range exceeded */
#define QRTCAN_SDO_ABORT_TOO_HIGH 0x06090031u
#define QRTCAN_SDO_ABORT_TOO_LOW 0x06090032u
#define QRTCAN_SDO_ABORT_GENERAL 0x08000000u
#define QRTCAN_SDO_ABORT_STATE 0x08000022u /* not in the present state */

/* Client -> server node (COB-ID 0x600 + node): READ, WRITE or ABORT. */
int qrtcan_sdo_encode_request(unsigned node, const struct qrtcan_sdo *s,
                              struct qrtcan_frame *f);
/* Server side. *node is the addressed server. */
int qrtcan_sdo_decode_request(const struct qrtcan_frame *f, unsigned *node,
                              struct qrtcan_sdo *s);
/* Server node -> client (COB-ID 0x580 + node): READ_OK, WRITE_OK, ABORT. */
int qrtcan_sdo_encode_response(unsigned node, const struct qrtcan_sdo *s,
                               struct qrtcan_frame *f);
/* Client side. *node is the answering server. A segmented upload response
 * (object longer than four bytes) is QRTCAN_E_UNSUPP. */
int qrtcan_sdo_decode_response(const struct qrtcan_frame *f, unsigned *node,
                               struct qrtcan_sdo *s);

/* The value of an expedited transfer sign-extended from its size (0 = 4). */
int32_t qrtcan_sdo_signed(const struct qrtcan_sdo *s);

#ifdef __cplusplus
}
#endif

#endif
