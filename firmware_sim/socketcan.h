/* struct can_driver on a Linux SocketCAN interface (vcan0, can0, ...). */
#ifndef FIRMWARE_SIM_SOCKETCAN_H
#define FIRMWARE_SIM_SOCKETCAN_H

#include "can_driver.h"

struct socketcan {
    int fd;
    unsigned long dropped; /* frames the kernel refused (queue full) */
};

/* 0, or -1 with errno set and a message on stderr. */
int socketcan_open(struct socketcan *s, const char *ifname,
                   struct can_driver *drv);
void socketcan_close(struct socketcan *s);

#endif
