/* SYNC (CiA 301 7.2.5): COB-ID 0x080, no data, or one counter byte 1..240
 * when the producer's synchronous counter overflow value is set. */
#ifndef QRTCAN_SYNC_H
#define QRTCAN_SYNC_H

#include "qrtcan/frame.h"

#ifdef __cplusplus
extern "C" {
#endif

#define QRTCAN_SYNC_COB_ID 0x080u

/* counter 0: a SYNC without data; 1..240: with that counter. */
int qrtcan_sync_encode(unsigned counter, struct qrtcan_frame *f);
/* *counter is 0 for a SYNC without data. */
int qrtcan_sync_decode(const struct qrtcan_frame *f, unsigned *counter);

#ifdef __cplusplus
}
#endif

#endif
