// Datagrams the kernel dropped on this process's UDP sockets (LCM's: the
// daemon has no other), because the receive buffer was full: scans lost
// before LCM could read them. Linux only (/proc/net/udp's "drops"); 0
// where that cannot be read.
#pragma once

#include <cstdint>

namespace qrt
{

int64_t lcm_datagrams_lost();

} // namespace qrt
