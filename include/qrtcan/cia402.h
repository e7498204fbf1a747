/* CiA 402 drive profile: the power state machine and the process data of
 * profile position mode.
 *
 * Two sides share this header. A drive decodes controlwords into commands
 * and steps its state with qrtcan_402_transition(); a master decodes
 * statuswords into states and asks qrtcan_402_controlword_toward() what to
 * send next to reach Operation Enabled (or to shut a drive down).
 *
 * Process data (this project's fixed PDO mapping, see can/servo_sim.eds):
 *   RPDO1 0x200 + node, 6 bytes: controlword (0x6040) u16, target (0x607A) i32
 *   TPDO1 0x180 + node, 6 bytes: statusword (0x6041) u16, position (0x6064) i32
 */
#ifndef QRTCAN_CIA402_H
#define QRTCAN_CIA402_H

#include "qrtcan/frame.h"

#ifdef __cplusplus
extern "C" {
#endif

/* Controlword (0x6040) bits. */
#define QRTCAN_CW_SWITCH_ON 0x0001u
#define QRTCAN_CW_ENABLE_VOLTAGE 0x0002u
#define QRTCAN_CW_QUICK_STOP 0x0004u /* active low: 0 = quick stop */
#define QRTCAN_CW_ENABLE_OPERATION 0x0008u
#define QRTCAN_CW_NEW_SETPOINT 0x0010u /* profile position: rising edge */
#define QRTCAN_CW_CHANGE_IMMEDIATELY 0x0020u
#define QRTCAN_CW_RELATIVE 0x0040u
#define QRTCAN_CW_FAULT_RESET 0x0080u /* rising edge */
#define QRTCAN_CW_HALT 0x0100u

/* Controlwords of the device control commands (CiA 402 table 30). */
#define QRTCAN_CW_CMD_SHUTDOWN 0x0006u
#define QRTCAN_CW_CMD_SWITCH_ON 0x0007u
#define QRTCAN_CW_CMD_DISABLE_VOLTAGE 0x0000u
#define QRTCAN_CW_CMD_QUICK_STOP 0x0002u
#define QRTCAN_CW_CMD_DISABLE_OPERATION 0x0007u
#define QRTCAN_CW_CMD_ENABLE_OPERATION 0x000Fu
#define QRTCAN_CW_CMD_FAULT_RESET 0x0080u

/* Statusword (0x6041) bits. */
#define QRTCAN_SW_READY_TO_SWITCH_ON 0x0001u
#define QRTCAN_SW_SWITCHED_ON 0x0002u
#define QRTCAN_SW_OPERATION_ENABLED 0x0004u
#define QRTCAN_SW_FAULT 0x0008u
#define QRTCAN_SW_VOLTAGE_ENABLED 0x0010u
#define QRTCAN_SW_QUICK_STOP 0x0020u /* active low: 0 = quick stop active */
#define QRTCAN_SW_SWITCH_ON_DISABLED 0x0040u
#define QRTCAN_SW_WARNING 0x0080u
#define QRTCAN_SW_REMOTE 0x0200u
#define QRTCAN_SW_TARGET_REACHED 0x0400u
#define QRTCAN_SW_INTERNAL_LIMIT 0x0800u
#define QRTCAN_SW_SETPOINT_ACK 0x1000u /* profile position */
#define QRTCAN_SW_FOLLOWING_ERROR 0x2000u

/* Modes of operation (0x6060 / 0x6061). */
#define QRTCAN_MODE_PROFILE_POSITION 1

enum qrtcan_402_state {
    QRTCAN_402_NOT_READY_TO_SWITCH_ON,
    QRTCAN_402_SWITCH_ON_DISABLED,
    QRTCAN_402_READY_TO_SWITCH_ON,
    QRTCAN_402_SWITCHED_ON,
    QRTCAN_402_OPERATION_ENABLED,
    QRTCAN_402_QUICK_STOP_ACTIVE,
    QRTCAN_402_FAULT_REACTION_ACTIVE,
    QRTCAN_402_FAULT,
    QRTCAN_402_UNKNOWN /* a statusword matching no state */
};

enum qrtcan_402_cmd {
    QRTCAN_402_CMD_NONE, /* nothing this state acts on */
    QRTCAN_402_CMD_SHUTDOWN,
    QRTCAN_402_CMD_SWITCH_ON, /* = disable operation in Operation Enabled */
    QRTCAN_402_CMD_ENABLE_OPERATION,
    QRTCAN_402_CMD_DISABLE_VOLTAGE,
    QRTCAN_402_CMD_QUICK_STOP,
    QRTCAN_402_CMD_FAULT_RESET
};

/* Master side: the state a statusword reports (bits 0-3, 5, 6). */
enum qrtcan_402_state qrtcan_402_state_from_statusword(uint16_t sw);

/* Drive side: the state bits of the statusword (0-3, 4, 5, 6) for a state;
 * the caller ORs in the other bits (remote, target reached, ...). */
uint16_t qrtcan_402_statusword_bits(enum qrtcan_402_state st);

/* Drive side: which command a controlword gives, given the previous one
 * (fault reset acts on the rising edge of bit 7 and wins over the rest). */
enum qrtcan_402_cmd qrtcan_402_command(uint16_t prev_cw, uint16_t cw);

/* Drive side: the state after command cmd in state st (CiA 402 figure 10,
 * transitions 2-12, 15, 16). The automatic transitions (0, 1: power-up;
 * 13, 14: fault) are the drive's to make. A quick stop from Operation
 * Enabled goes to Quick Stop Active; the drive stays there until disable
 * voltage or enable operation (quick stop option code 5/6 behaviour). */
enum qrtcan_402_state qrtcan_402_transition(enum qrtcan_402_state st,
                                            enum qrtcan_402_cmd cmd);

/* Master side: the controlword that moves a drive in state st one step
 * towards target (QRTCAN_402_OPERATION_ENABLED, or SWITCH_ON_DISABLED to
 * shut it down). prev_cw is the controlword sent last: leaving Fault
 * needs bit 7 to rise, so from Fault this alternates 0x0000 and 0x0080.
 * Returns prev_cw's non-state bits cleared; in the target state it returns
 * the command that holds it. */
uint16_t qrtcan_402_controlword_toward(enum qrtcan_402_state st,
                                       enum qrtcan_402_state target,
                                       uint16_t prev_cw);

const char *qrtcan_402_state_name(enum qrtcan_402_state st);

struct qrtcan_402_rpdo {
    uint16_t controlword;
    int32_t target_position; /* drive counts */
};

struct qrtcan_402_tpdo {
    uint16_t statusword;
    int32_t position_actual; /* drive counts */
};

int qrtcan_402_rpdo_encode(unsigned node, const struct qrtcan_402_rpdo *p,
                           struct qrtcan_frame *f);
int qrtcan_402_rpdo_decode(const struct qrtcan_frame *f, unsigned *node,
                           struct qrtcan_402_rpdo *p);
int qrtcan_402_tpdo_encode(unsigned node, const struct qrtcan_402_tpdo *p,
                           struct qrtcan_frame *f);
int qrtcan_402_tpdo_decode(const struct qrtcan_frame *f, unsigned *node,
                           struct qrtcan_402_tpdo *p);

#ifdef __cplusplus
}
#endif

#endif
