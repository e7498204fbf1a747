#include "qrtcan/emcy.h"

#include <stddef.h>
#include <string.h>

int qrtcan_emcy_encode(unsigned node, const struct qrtcan_emcy *e,
                       struct qrtcan_frame *f)
{
    if (f == NULL || e == NULL) {
        return QRTCAN_E_ARG;
    }
    if (!qrtcan_node_valid(node)) {
        return QRTCAN_E_NODE;
    }
    memset(f, 0, sizeof *f);
    f->id = qrtcan_cob_id(QRTCAN_FN_SYNC_EMCY, node);
    f->dlc = 8;
    qrtcan_put_u16(f->data, e->code);
    f->data[2] = e->error_register;
    memcpy(&f->data[3], e->vendor, sizeof e->vendor);
    return QRTCAN_OK;
}

int qrtcan_emcy_decode(const struct qrtcan_frame *f, unsigned *node,
                       struct qrtcan_emcy *e)
{
    if (f == NULL || node == NULL || e == NULL) {
        return QRTCAN_E_ARG;
    }
    if (f->id <= QRTCAN_FN_SYNC_EMCY || f->id > 0x0FFu) {
        return QRTCAN_E_ID;
    }
    if (f->dlc != 8) {
        return QRTCAN_E_DLC;
    }
    *node = (unsigned)(f->id - QRTCAN_FN_SYNC_EMCY);
    e->code = qrtcan_get_u16(f->data);
    e->error_register = f->data[2];
    memcpy(e->vendor, &f->data[3], sizeof e->vendor);
    return QRTCAN_OK;
}
