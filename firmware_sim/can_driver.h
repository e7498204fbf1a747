/* The only thing the drive firmware knows about the hardware: a CAN
 * controller that sends and receives frames, and a microsecond clock.
 * socketcan.c is the Linux implementation; a board would wrap its CAN
 * peripheral the same way, and the unit tests wrap a queue in memory. */
#ifndef FIRMWARE_SIM_CAN_DRIVER_H
#define FIRMWARE_SIM_CAN_DRIVER_H

#include <stdint.h>

#include "qrtcan/frame.h"

struct can_driver {
    void *ctx;
    /* 0 when queued; negative when the frame was dropped (bus full) */
    int (*send)(void *ctx, const struct qrtcan_frame *f);
    /* 1 with a frame in *f, 0 when timeout_us passed without one,
     * negative on a driver error */
    int (*receive)(void *ctx, struct qrtcan_frame *f, uint32_t timeout_us);
    /* monotonic microseconds */
    uint64_t (*now_us)(void *ctx);
};

#endif
