#include "qrtcan/sync.h"

#include <stddef.h>
#include <string.h>

/* CiA 301: the synchronous counter overflow value is 2..240. */
#define SYNC_COUNTER_MAX 240u

int qrtcan_sync_encode(unsigned counter, struct qrtcan_frame *f)
{
    if (f == NULL || counter > SYNC_COUNTER_MAX) {
        return QRTCAN_E_ARG;
    }
    memset(f, 0, sizeof *f);
    f->id = QRTCAN_SYNC_COB_ID;
    f->dlc = counter == 0 ? 0 : 1;
    f->data[0] = (uint8_t)counter;
    return QRTCAN_OK;
}

int qrtcan_sync_decode(const struct qrtcan_frame *f, unsigned *counter)
{
    if (f == NULL || counter == NULL) {
        return QRTCAN_E_ARG;
    }
    if (f->id != QRTCAN_SYNC_COB_ID) {
        return QRTCAN_E_ID;
    }
    if (f->dlc > 1) {
        return QRTCAN_E_DLC;
    }
    if (f->dlc == 1 && (f->data[0] == 0 || f->data[0] > SYNC_COUNTER_MAX)) {
        return QRTCAN_E_RANGE;
    }
    *counter = f->dlc == 1 ? f->data[0] : 0;
    return QRTCAN_OK;
}
