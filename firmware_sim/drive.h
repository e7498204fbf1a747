/* One simulated CiA 402 servo drive, written as its firmware would be:
 * portable C99, no OS, no malloc; it sees the bus only through struct
 * can_driver. The main loop feeds it every received frame and calls
 * drive_tick() about once a millisecond.
 *
 * It implements: NMT slave with boot-up and heartbeat producer (0x1017);
 * an expedited SDO server on its object dictionary (drive.c's table);
 * RPDO1 (controlword, target) acted on at once and TPDO1 (statusword,
 * position actual) sent after every SYNC; the CiA 402 power state machine;
 * profile position mode with a trapezoidal velocity profile that settles
 * at target + a steady-state error (the paper's servo error, 0x2001);
 * software position limits (0x607D); CiA 301's heartbeat consumer
 * (0x1016: a configured node's heartbeat missing for its time -> EMCY
 * 0x8130 and the abort connection option 0x6007); a vendor SYNC watchdog
 * (0x2000: no SYNC for that long -> the same reaction); injected faults
 * (EMCY, Fault Reaction Active, Fault).
 */
#ifndef FIRMWARE_SIM_DRIVE_H
#define FIRMWARE_SIM_DRIVE_H

#include <stdint.h>

#include "can_driver.h"
#include "qrtcan/cia402.h"
#include "qrtcan/nmt.h"

/* Entries of the heartbeat consumer (0x1016:1..N). */
#define DRIVE_HB_CONSUMERS 4u

/* Monitoring of one heartbeat consumer entry. */
enum drive_hb_watch {
    DRIVE_HB_IDLE,   /* unused, or no heartbeat from its node since the
                        entry was written: not monitored */
    DRIVE_HB_ARMED,  /* heartbeats arrive; their absence is an event */
    DRIVE_HB_EXPIRED /* the event fired; the next heartbeat re-arms it */
};

struct drive_config {
    unsigned node;          /* 1..127 */
    int32_t limit_min;      /* 0x607D:1, counts */
    int32_t limit_max;      /* 0x607D:2 */
    int32_t servo_error;    /* 0x2001: settles at target + this, counts */
    uint32_t watchdog_ms;   /* 0x2000, SYNC loss: 0 = off */
    uint16_t heartbeat_ms;  /* 0x1017: 0 = off */
    int32_t start_position; /* counts at power-up */
};

struct drive {
    struct drive_config cfg;
    /* communication and state */
    uint8_t nmt; /* enum qrtcan_nmt_state */
    enum qrtcan_402_state state;
    int muted; /* sends nothing, answers nothing (a dead node) */
    uint64_t next_heartbeat_us;
    uint64_t last_sync_us; /* last SYNC, 0 = none yet */
    int watchdog_tripped;
    /* heartbeat consumer: per 0x1016 entry, its monitoring and the time
     * of the last heartbeat received from its node */
    uint8_t hb_watch[DRIVE_HB_CONSUMERS]; /* enum drive_hb_watch */
    uint64_t hb_seen_us[DRIVE_HB_CONSUMERS];
    uint64_t last_tick_us;
    /* motion, in counts */
    double pos, vel;
    int32_t setpoint; /* the accepted target of profile position */
    int moving, halted_reached, limit_active, setpoint_ack;
    /* object dictionary (drive.c lists index, subindex, size, access) */
    uint32_t device_type;                     /* 0x1000 */
    uint8_t error_register;                   /* 0x1001 */
    uint8_t hb_consumer_count;                /* 0x1016:0 */
    uint32_t hb_consumer[DRIVE_HB_CONSUMERS]; /* 0x1016:1..4 */
    uint16_t heartbeat_ms;                    /* 0x1017 */
    uint8_t identity_count;                   /* 0x1018:0 */
    uint32_t identity[4];                     /* 0x1018:1..4 */
    uint8_t pdo_comm_count, pdo_map_count;
    uint32_t rpdo_cob_id, tpdo_cob_id; /* 0x1400:1, 0x1800:1 */
    uint8_t rpdo_type, tpdo_type;      /* 0x1400:2, 0x1800:2 */
    uint32_t rpdo_map[2], tpdo_map[2]; /* 0x1600:1..2, 0x1A00:1..2 */
    uint32_t watchdog_ms;              /* 0x2000 */
    int32_t servo_error;               /* 0x2001 */
    uint16_t error_code;               /* 0x603F */
    uint16_t controlword;              /* 0x6040 */
    uint16_t statusword;               /* 0x6041 */
    int16_t abort_option;              /* 0x6007: none/fault/off/qs, 0..3 */
    int8_t mode;                       /* 0x6060 */
    int8_t mode_display;               /* 0x6061 */
    int32_t position_actual;           /* 0x6064 */
    int32_t velocity_actual;           /* 0x606C */
    uint32_t position_window;          /* 0x6067 */
    int32_t target;                    /* 0x607A */
    uint8_t limit_count;               /* 0x607D:0 */
    int32_t limit[2];                  /* 0x607D:1..2 */
    uint32_t profile_velocity;         /* 0x6081, counts/s */
    uint32_t profile_accel;            /* 0x6083, counts/s^2 */
    uint32_t profile_decel;            /* 0x6084 */
    uint32_t quick_stop_decel;         /* 0x6085 */
    uint32_t supported_modes;          /* 0x6502 */
};

/* Power-up: object dictionary defaults, boot-up message, Pre-operational. */
void drive_init(struct drive *d, const struct drive_config *cfg,
                const struct can_driver *can);
/* Every frame off the bus; frames for other nodes are ignored. */
void drive_on_frame(struct drive *d, const struct qrtcan_frame *f,
                    const struct can_driver *can);
/* Motion, heartbeat producer and consumer, watchdog, fault reaction. */
void drive_tick(struct drive *d, const struct can_driver *can);
/* A fault inside the drive (over current, ...): EMCY with code, then
 * Fault Reaction Active (quick stop ramp) and Fault. */
void drive_fault(struct drive *d, uint16_t code, const struct can_driver *can);

#endif
