/* NMT module control (master -> nodes) and heartbeat (node -> everyone):
 * CiA 301 7.2.8. */
#ifndef QRTCAN_NMT_H
#define QRTCAN_NMT_H

#include "qrtcan/frame.h"

#ifdef __cplusplus
extern "C" {
#endif

enum qrtcan_nmt_cmd {
    QRTCAN_NMT_START = 0x01,
    QRTCAN_NMT_STOP = 0x02,
    QRTCAN_NMT_PRE_OPERATIONAL = 0x80,
    QRTCAN_NMT_RESET_NODE = 0x81,
    QRTCAN_NMT_RESET_COMM = 0x82,
};

/* NMT states as a heartbeat carries them. */
enum qrtcan_nmt_state {
    QRTCAN_NMT_BOOTUP = 0x00,
    QRTCAN_NMT_STOPPED = 0x04,
    QRTCAN_NMT_OPERATIONAL = 0x05,
    QRTCAN_NMT_PRE_OP = 0x7F,
};

/* node 0 addresses every node. */
int qrtcan_nmt_encode(enum qrtcan_nmt_cmd cmd, unsigned node,
                      struct qrtcan_frame *f);
/* *node is 0 for a broadcast. */
int qrtcan_nmt_decode(const struct qrtcan_frame *f, enum qrtcan_nmt_cmd *cmd,
                      unsigned *node);
/* 1 if an NMT command addressed to target (0 = broadcast) concerns node. */
int qrtcan_nmt_addressed_to(unsigned target, unsigned node);

int qrtcan_heartbeat_encode(unsigned node, enum qrtcan_nmt_state state,
                            struct qrtcan_frame *f);
/* The toggle bit (bit 7, node guarding only) is ignored. */
int qrtcan_heartbeat_decode(const struct qrtcan_frame *f, unsigned *node,
                            enum qrtcan_nmt_state *state);

#ifdef __cplusplus
}
#endif

#endif
