/* The tests' CAN bus in memory: the master's driver (struct can_driver)
 * appends what it sends to bus[], which the test delivers to its simulated
 * drives and then empties; receive has nothing (the test delivers the
 * drives' answers itself); the clock is the test's clock_us. One
 * definition for each test program that includes it (test_master.c,
 * test_setpoints.c). */
#ifndef QRT_TEST_MEM_BUS_H
#define QRT_TEST_MEM_BUS_H

#include <stdint.h>

#include "qrtcan/master.h"

#define BUS_MAX 4096

static struct qrtcan_frame bus[BUS_MAX];
static int bus_count;
static uint64_t clock_us = 1000;
static unsigned long frames_lost; /* sends refused on a full bus */

static int mem_send(void *ctx, const struct qrtcan_frame *f)
{
    (void)ctx;
    if (bus_count == BUS_MAX) {
        frames_lost++;
        return -1;
    }
    bus[bus_count++] = *f;
    return 0;
}

static int mem_receive(void *ctx, struct qrtcan_frame *f, uint32_t timeout)
{
    (void)ctx;
    (void)f;
    (void)timeout;
    return 0;
}

static uint64_t mem_now(void *ctx)
{
    (void)ctx;
    return clock_us;
}

static const struct can_driver can = {NULL, mem_send, mem_receive, mem_now};

#endif
