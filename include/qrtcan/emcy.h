/* Emergency messages (CiA 301 7.2.7): 0x080 + node, eight bytes: error
 * code, error register (object 0x1001), five manufacturer bytes. */
#ifndef QRTCAN_EMCY_H
#define QRTCAN_EMCY_H

#include "qrtcan/frame.h"

#ifdef __cplusplus
extern "C" {
#endif

/* Error codes used in this project (CiA 301 table 21, CiA 402 annex). */
#define QRTCAN_EMCY_NO_ERROR 0x0000u /* error reset or no error */
#define QRTCAN_EMCY_GENERIC 0x1000u
#define QRTCAN_EMCY_OVERCURRENT 0x2310u /* continuous over current */
#define QRTCAN_EMCY_COMM 0x8100u        /* communication, generic */
#define QRTCAN_EMCY_HEARTBEAT 0x8130u   /* life guard / heartbeat error */
#define QRTCAN_EMCY_FOLLOWING 0x8611u   /* following error */
#define QRTCAN_EMCY_SOFT_LIMIT 0x8612u  /* reference limit */

/* Error register bits (object 0x1001). */
#define QRTCAN_ERRREG_GENERIC 0x01u
#define QRTCAN_ERRREG_CURRENT 0x02u
#define QRTCAN_ERRREG_COMM 0x10u

struct qrtcan_emcy {
    uint16_t code;
    uint8_t error_register;
    uint8_t vendor[5];
};

int qrtcan_emcy_encode(unsigned node, const struct qrtcan_emcy *e,
                       struct qrtcan_frame *f);
/* Refuses the SYNC identifier (0x080) and any DLC but 8. */
int qrtcan_emcy_decode(const struct qrtcan_frame *f, unsigned *node,
                       struct qrtcan_emcy *e);

#ifdef __cplusplus
}
#endif

#endif
