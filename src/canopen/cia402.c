#include "qrtcan/cia402.h"

#include <stddef.h>
#include <string.h>

enum qrtcan_402_state qrtcan_402_state_from_statusword(uint16_t sw)
{
    /* CiA 402 table 31: bits 0-3 and 6 always, bit 5 where it tells
     * Quick Stop Active from Operation Enabled */
    unsigned s = sw & 0x4Fu, q = sw & 0x6Fu;
    if (s == 0x00u) {
        return QRTCAN_402_NOT_READY_TO_SWITCH_ON;
    }
    if (s == 0x40u) {
        return QRTCAN_402_SWITCH_ON_DISABLED;
    }
    if (q == 0x21u) {
        return QRTCAN_402_READY_TO_SWITCH_ON;
    }
    if (q == 0x23u) {
        return QRTCAN_402_SWITCHED_ON;
    }
    if (q == 0x27u) {
        return QRTCAN_402_OPERATION_ENABLED;
    }
    if (q == 0x07u) {
        return QRTCAN_402_QUICK_STOP_ACTIVE;
    }
    if (s == 0x0Fu) {
        return QRTCAN_402_FAULT_REACTION_ACTIVE;
    }
    if (s == 0x08u) {
        return QRTCAN_402_FAULT;
    }
    return QRTCAN_402_UNKNOWN;
}

uint16_t qrtcan_402_statusword_bits(enum qrtcan_402_state st)
{
    switch (st) {
    case QRTCAN_402_SWITCH_ON_DISABLED:
        return 0x0040u;
    case QRTCAN_402_READY_TO_SWITCH_ON:
        return 0x0031u;
    case QRTCAN_402_SWITCHED_ON:
        return 0x0033u;
    case QRTCAN_402_OPERATION_ENABLED:
        return 0x0037u;
    case QRTCAN_402_QUICK_STOP_ACTIVE:
        return 0x0017u;
    case QRTCAN_402_FAULT_REACTION_ACTIVE:
        return 0x001Fu;
    case QRTCAN_402_FAULT:
        return 0x0008u;
    case QRTCAN_402_NOT_READY_TO_SWITCH_ON:
    default:
        return 0x0000u;
    }
}

enum qrtcan_402_cmd qrtcan_402_command(uint16_t prev_cw, uint16_t cw)
{
    /* Bit 7 held high after a reset is ignored rather than read as "no
     * command": masters differ in when they clear it. */
    if ((prev_cw & QRTCAN_CW_FAULT_RESET) == 0 &&
        (cw & QRTCAN_CW_FAULT_RESET) != 0) {
        return QRTCAN_402_CMD_FAULT_RESET;
    }
    if ((cw & 0x02u) == 0) {
        return QRTCAN_402_CMD_DISABLE_VOLTAGE;
    }
    if ((cw & 0x06u) == 0x02u) {
        return QRTCAN_402_CMD_QUICK_STOP;
    }
    if ((cw & 0x07u) == 0x06u) {
        return QRTCAN_402_CMD_SHUTDOWN;
    }
    if ((cw & 0x0Fu) == 0x07u) {
        return QRTCAN_402_CMD_SWITCH_ON;
    }
    return QRTCAN_402_CMD_ENABLE_OPERATION; /* x111 1 is all that is left */
}

/* The transitions out of each state that takes more than one command, a
 * function each (a switch inside a switch clause leaves that clause without
 * its break, MISRA C:2012 rule 16.3). */
static enum qrtcan_402_state from_ready_to_switch_on(enum qrtcan_402_cmd cmd)
{
    switch (cmd) {
    case QRTCAN_402_CMD_SWITCH_ON:
        return QRTCAN_402_SWITCHED_ON;
    case QRTCAN_402_CMD_ENABLE_OPERATION: /* 3 then 4 at once */
        return QRTCAN_402_OPERATION_ENABLED;
    case QRTCAN_402_CMD_DISABLE_VOLTAGE:
    case QRTCAN_402_CMD_QUICK_STOP:
        return QRTCAN_402_SWITCH_ON_DISABLED;
    default:
        return QRTCAN_402_READY_TO_SWITCH_ON;
    }
}

static enum qrtcan_402_state from_switched_on(enum qrtcan_402_cmd cmd)
{
    switch (cmd) {
    case QRTCAN_402_CMD_ENABLE_OPERATION:
        return QRTCAN_402_OPERATION_ENABLED;
    case QRTCAN_402_CMD_SHUTDOWN:
        return QRTCAN_402_READY_TO_SWITCH_ON;
    case QRTCAN_402_CMD_DISABLE_VOLTAGE:
    case QRTCAN_402_CMD_QUICK_STOP:
        return QRTCAN_402_SWITCH_ON_DISABLED;
    default:
        return QRTCAN_402_SWITCHED_ON;
    }
}

static enum qrtcan_402_state from_operation_enabled(enum qrtcan_402_cmd cmd)
{
    switch (cmd) {
    case QRTCAN_402_CMD_SWITCH_ON:
        return QRTCAN_402_SWITCHED_ON;
    case QRTCAN_402_CMD_SHUTDOWN:
        return QRTCAN_402_READY_TO_SWITCH_ON;
    case QRTCAN_402_CMD_DISABLE_VOLTAGE:
        return QRTCAN_402_SWITCH_ON_DISABLED;
    case QRTCAN_402_CMD_QUICK_STOP:
        return QRTCAN_402_QUICK_STOP_ACTIVE;
    default:
        return QRTCAN_402_OPERATION_ENABLED;
    }
}

static enum qrtcan_402_state from_quick_stop_active(enum qrtcan_402_cmd cmd)
{
    switch (cmd) {
    case QRTCAN_402_CMD_DISABLE_VOLTAGE:
        return QRTCAN_402_SWITCH_ON_DISABLED;
    case QRTCAN_402_CMD_ENABLE_OPERATION:
        return QRTCAN_402_OPERATION_ENABLED;
    default:
        return QRTCAN_402_QUICK_STOP_ACTIVE;
    }
}

enum qrtcan_402_state qrtcan_402_transition(enum qrtcan_402_state st,
                                            enum qrtcan_402_cmd cmd)
{
    switch (st) {
    case QRTCAN_402_SWITCH_ON_DISABLED:
        return cmd == QRTCAN_402_CMD_SHUTDOWN ? QRTCAN_402_READY_TO_SWITCH_ON
                                              : st;
    case QRTCAN_402_READY_TO_SWITCH_ON:
        return from_ready_to_switch_on(cmd);
    case QRTCAN_402_SWITCHED_ON:
        return from_switched_on(cmd);
    case QRTCAN_402_OPERATION_ENABLED:
        return from_operation_enabled(cmd);
    case QRTCAN_402_QUICK_STOP_ACTIVE:
        return from_quick_stop_active(cmd);
    case QRTCAN_402_FAULT:
        return cmd == QRTCAN_402_CMD_FAULT_RESET ? QRTCAN_402_SWITCH_ON_DISABLED
                                                 : st;
    default:
        return st;
    }
}

/* The next command on the way to Operation Enabled, and to Switched On. */
static uint16_t toward_operation_enabled(enum qrtcan_402_state st)
{
    switch (st) {
    case QRTCAN_402_SWITCH_ON_DISABLED:
        return QRTCAN_CW_CMD_SHUTDOWN;
    case QRTCAN_402_READY_TO_SWITCH_ON:
        return QRTCAN_CW_CMD_SWITCH_ON;
    case QRTCAN_402_SWITCHED_ON:
    case QRTCAN_402_OPERATION_ENABLED:
        return QRTCAN_CW_CMD_ENABLE_OPERATION;
    default:
        /* Quick Stop Active goes round by Switch On Disabled: after a
         * quick stop the master should pass through every state again
         * rather than re-enable with transition 16 */
        return QRTCAN_CW_CMD_DISABLE_VOLTAGE;
    }
}

static uint16_t toward_switched_on(enum qrtcan_402_state st)
{
    switch (st) {
    case QRTCAN_402_SWITCH_ON_DISABLED:
        return QRTCAN_CW_CMD_SHUTDOWN;
    case QRTCAN_402_READY_TO_SWITCH_ON:
    case QRTCAN_402_SWITCHED_ON:
    case QRTCAN_402_OPERATION_ENABLED:
        return QRTCAN_CW_CMD_SWITCH_ON;
    default:
        return QRTCAN_CW_CMD_DISABLE_VOLTAGE;
    }
}

uint16_t qrtcan_402_controlword_toward(enum qrtcan_402_state st,
                                       enum qrtcan_402_state target,
                                       uint16_t prev_cw)
{
    if (st == QRTCAN_402_FAULT) {
        return (prev_cw & QRTCAN_CW_FAULT_RESET) ? QRTCAN_CW_CMD_DISABLE_VOLTAGE
                                                 : QRTCAN_CW_CMD_FAULT_RESET;
    }
    switch (target) {
    case QRTCAN_402_OPERATION_ENABLED:
        return toward_operation_enabled(st);
    case QRTCAN_402_SWITCHED_ON:
        return toward_switched_on(st);
    case QRTCAN_402_READY_TO_SWITCH_ON:
        return st == QRTCAN_402_QUICK_STOP_ACTIVE ||
                       st == QRTCAN_402_FAULT_REACTION_ACTIVE
                   ? QRTCAN_CW_CMD_DISABLE_VOLTAGE
                   : QRTCAN_CW_CMD_SHUTDOWN;
    default:
        return QRTCAN_CW_CMD_DISABLE_VOLTAGE;
    }
}

const char *qrtcan_402_state_name(enum qrtcan_402_state st)
{
    switch (st) {
    case QRTCAN_402_NOT_READY_TO_SWITCH_ON:
        return "NOT READY TO SWITCH ON";
    case QRTCAN_402_SWITCH_ON_DISABLED:
        return "SWITCH ON DISABLED";
    case QRTCAN_402_READY_TO_SWITCH_ON:
        return "READY TO SWITCH ON";
    case QRTCAN_402_SWITCHED_ON:
        return "SWITCHED ON";
    case QRTCAN_402_OPERATION_ENABLED:
        return "OPERATION ENABLED";
    case QRTCAN_402_QUICK_STOP_ACTIVE:
        return "QUICK STOP ACTIVE";
    case QRTCAN_402_FAULT_REACTION_ACTIVE:
        return "FAULT REACTION ACTIVE";
    case QRTCAN_402_FAULT:
        return "FAULT";
    default:
        return "UNKNOWN";
    }
}

static int pdo_encode(uint32_t fn, unsigned node, uint16_t word, int32_t pos,
                      struct qrtcan_frame *f)
{
    if (!qrtcan_node_valid(node)) {
        return QRTCAN_E_NODE;
    }
    memset(f, 0, sizeof *f);
    f->id = fn + node;
    f->dlc = 6;
    qrtcan_put_u16(f->data, word);
    qrtcan_put_u32(&f->data[2], (uint32_t)pos);
    return QRTCAN_OK;
}

static int pdo_decode(const struct qrtcan_frame *f, uint32_t fn, unsigned *node,
                      uint16_t *word, int32_t *pos)
{
    uint32_t v;
    if (f->id <= fn || f->id > fn + QRTCAN_NODE_MAX) {
        return QRTCAN_E_ID;
    }
    /* the mapping is exactly 48 bits: a shorter PDO lacks fields, a longer
     * one belongs to another mapping */
    if (f->dlc != 6) {
        return QRTCAN_E_DLC;
    }
    *node = (unsigned)(f->id - fn);
    *word = qrtcan_get_u16(f->data);
    v = qrtcan_get_u32(&f->data[2]);
    *pos = (v & 0x80000000u) ? -(int32_t)(~v) - 1 : (int32_t)v;
    return QRTCAN_OK;
}

int qrtcan_402_rpdo_encode(unsigned node, const struct qrtcan_402_rpdo *p,
                           struct qrtcan_frame *f)
{
    if (p == NULL || f == NULL) {
        return QRTCAN_E_ARG;
    }
    return pdo_encode(QRTCAN_FN_RPDO1, node, p->controlword, p->target_position,
                      f);
}

int qrtcan_402_rpdo_decode(const struct qrtcan_frame *f, unsigned *node,
                           struct qrtcan_402_rpdo *p)
{
    if (f == NULL || node == NULL || p == NULL) {
        return QRTCAN_E_ARG;
    }
    return pdo_decode(f, QRTCAN_FN_RPDO1, node, &p->controlword,
                      &p->target_position);
}

int qrtcan_402_tpdo_encode(unsigned node, const struct qrtcan_402_tpdo *p,
                           struct qrtcan_frame *f)
{
    if (p == NULL || f == NULL) {
        return QRTCAN_E_ARG;
    }
    return pdo_encode(QRTCAN_FN_TPDO1, node, p->statusword, p->position_actual,
                      f);
}

int qrtcan_402_tpdo_decode(const struct qrtcan_frame *f, unsigned *node,
                           struct qrtcan_402_tpdo *p)
{
    if (f == NULL || node == NULL || p == NULL) {
        return QRTCAN_E_ARG;
    }
    return pdo_decode(f, QRTCAN_FN_TPDO1, node, &p->statusword,
                      &p->position_actual);
}
