#include "qrtcan/nmt.h"

#include <stddef.h>
#include <string.h>

static int nmt_cmd_valid(unsigned c)
{
    return c == QRTCAN_NMT_START || c == QRTCAN_NMT_STOP ||
           c == QRTCAN_NMT_PRE_OPERATIONAL || c == QRTCAN_NMT_RESET_NODE ||
           c == QRTCAN_NMT_RESET_COMM;
}

static int nmt_state_valid(unsigned s)
{
    return s == QRTCAN_NMT_BOOTUP || s == QRTCAN_NMT_STOPPED ||
           s == QRTCAN_NMT_OPERATIONAL || s == QRTCAN_NMT_PRE_OP;
}

int qrtcan_nmt_encode(enum qrtcan_nmt_cmd cmd, unsigned node,
                      struct qrtcan_frame *f)
{
    if (f == NULL || !nmt_cmd_valid((unsigned)cmd)) {
        return QRTCAN_E_ARG;
    }
    if (node != 0 && !qrtcan_node_valid(node)) {
        return QRTCAN_E_NODE;
    }
    memset(f, 0, sizeof *f);
    f->id = 0;
    f->dlc = 2;
    f->data[0] = (uint8_t)cmd;
    f->data[1] = (uint8_t)node;
    return QRTCAN_OK;
}

int qrtcan_nmt_decode(const struct qrtcan_frame *f, enum qrtcan_nmt_cmd *cmd,
                      unsigned *node)
{
    if (f == NULL || cmd == NULL || node == NULL) {
        return QRTCAN_E_ARG;
    }
    if (f->id != 0) {
        return QRTCAN_E_ID;
    }
    if (f->dlc != 2) {
        return QRTCAN_E_DLC;
    }
    if (!nmt_cmd_valid(f->data[0])) {
        return QRTCAN_E_CMD;
    }
    if (f->data[1] != 0 && !qrtcan_node_valid(f->data[1])) {
        return QRTCAN_E_NODE;
    }
    *cmd = (enum qrtcan_nmt_cmd)f->data[0];
    *node = f->data[1];
    return QRTCAN_OK;
}

int qrtcan_nmt_addressed_to(unsigned target, unsigned node)
{
    return target == 0 || target == node;
}

int qrtcan_heartbeat_encode(unsigned node, enum qrtcan_nmt_state state,
                            struct qrtcan_frame *f)
{
    if (f == NULL || !nmt_state_valid((unsigned)state)) {
        return QRTCAN_E_ARG;
    }
    if (!qrtcan_node_valid(node)) {
        return QRTCAN_E_NODE;
    }
    memset(f, 0, sizeof *f);
    f->id = qrtcan_cob_id(QRTCAN_FN_HEARTBEAT, node);
    f->dlc = 1;
    f->data[0] = (uint8_t)state;
    return QRTCAN_OK;
}

int qrtcan_heartbeat_decode(const struct qrtcan_frame *f, unsigned *node,
                            enum qrtcan_nmt_state *state)
{
    unsigned s;
    if (f == NULL || node == NULL || state == NULL) {
        return QRTCAN_E_ARG;
    }
    if (f->id <= QRTCAN_FN_HEARTBEAT || f->id > 0x77Fu) {
        return QRTCAN_E_ID;
    }
    if (f->dlc != 1) {
        return QRTCAN_E_DLC;
    }
    s = f->data[0] & 0x7Fu;
    if (!nmt_state_valid(s)) {
        return QRTCAN_E_CMD;
    }
    *node = (unsigned)(f->id - QRTCAN_FN_HEARTBEAT);
    *state = (enum qrtcan_nmt_state)s;
    return QRTCAN_OK;
}
