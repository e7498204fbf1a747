#define _POSIX_C_SOURCE 200809L
#include "socketcan.h"

#include <errno.h>
#include <linux/can.h>
#include <linux/can/raw.h>
#include <net/if.h>
#include <poll.h>
#include <stdio.h>
#include <string.h>
#include <sys/socket.h>
#include <time.h>
#include <unistd.h>

static int sc_send(void *ctx, const struct qrtcan_frame *f)
{
    struct socketcan *s = ctx;
    struct can_frame cf;
    memset(&cf, 0, sizeof cf);
    cf.can_id = f->id & CAN_SFF_MASK;
    cf.can_dlc = f->dlc > 8 ? 8 : f->dlc;
    memcpy(cf.data, f->data, 8);
    if (write(s->fd, &cf, sizeof cf) != (ssize_t)sizeof cf) {
        s->dropped++;
        return -1;
    }
    return 0;
}

static int sc_receive(void *ctx, struct qrtcan_frame *f, uint32_t timeout_us)
{
    struct socketcan *s = ctx;
    struct pollfd p = {s->fd, POLLIN, 0};
    struct can_frame cf;
    ssize_t n;
    int rc = poll(&p, 1, (int)((timeout_us + 999u) / 1000u));
    if (rc <= 0) {
        return rc < 0 && errno != EINTR ? -1 : 0;
    }
    n = read(s->fd, &cf, sizeof cf);
    if (n != (ssize_t)sizeof cf) {
        return n < 0 && errno != EINTR && errno != EAGAIN ? -1 : 0;
    }
    /* extended, remote and error frames are not CANopen's: hand the drive
     * an identifier every decoder refuses */
    f->id = (cf.can_id & (CAN_EFF_FLAG | CAN_RTR_FLAG | CAN_ERR_FLAG))
                ? 0xFFFFFFFFu
                : (cf.can_id & CAN_SFF_MASK);
    f->dlc = cf.can_dlc;
    memcpy(f->data, cf.data, 8);
    return 1;
}

static uint64_t sc_now(void *ctx)
{
    struct timespec ts;
    (void)ctx;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (uint64_t)ts.tv_sec * 1000000u + (uint64_t)ts.tv_nsec / 1000u;
}

int socketcan_open(struct socketcan *s, const char *ifname,
                   struct can_driver *drv)
{
    struct sockaddr_can addr;
    unsigned idx;
    memset(s, 0, sizeof *s);
    s->fd = socket(PF_CAN, SOCK_RAW, CAN_RAW);
    if (s->fd < 0) {
        fprintf(stderr,
                "servo_sim: socket(AF_CAN): %s (no CAN in this kernel?)\n",
                strerror(errno));
        return -1;
    }
    idx = if_nametoindex(ifname);
    if (idx == 0) {
        fprintf(stderr, "servo_sim: no CAN interface %s: %s\n", ifname,
                strerror(errno));
        close(s->fd);
        return -1;
    }
    memset(&addr, 0, sizeof addr);
    addr.can_family = AF_CAN;
    addr.can_ifindex = (int)idx;
    if (bind(s->fd, (struct sockaddr *)&addr, sizeof addr) != 0) {
        fprintf(stderr, "servo_sim: bind %s: %s\n", ifname, strerror(errno));
        close(s->fd);
        return -1;
    }
    drv->ctx = s;
    drv->send = sc_send;
    drv->receive = sc_receive;
    drv->now_us = sc_now;
    return 0;
}

void socketcan_close(struct socketcan *s)
{
    if (s->fd >= 0) {
        close(s->fd);
        s->fd = -1;
    }
}
