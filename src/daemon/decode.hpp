// Decoding untrusted LCM bytes. lcm-gen's C++ decoders return a negative
// length for a wrong fingerprint or a short buffer, but a string whose
// length field is 0 or negative makes them throw std::length_error (found
// by tests/fuzz/fuzz_lcm.cpp): here every failure is a negative return.
#pragma once

#include <cstdint>
#include <exception>

namespace qrt
{

// LCM's integers are big-endian; the caller has checked that the bytes are
// there.
inline uint32_t lcm_u32(const uint8_t *p)
{
    return uint32_t(p[0]) << 24 | uint32_t(p[1]) << 16 | uint32_t(p[2]) << 8 |
           uint32_t(p[3]);
}

inline uint64_t lcm_u64(const uint8_t *p)
{
    return uint64_t(lcm_u32(p)) << 32 | lcm_u32(p + 4);
}

// An LCM string field at byte offset: its length (int32, big-endian,
// counting the NUL) must be 1..remaining. The generated decoder computes
// length - 1 in int before any check (undefined for INT_MIN), so strings
// are checked by hand first.
inline bool lcm_string_ok(const void *buf, int size, int offset)
{
    const uint8_t *b = static_cast<const uint8_t *>(buf);
    if (offset < 0 || size - offset < 4)
        return false;
    int64_t len = int32_t(lcm_u32(b + offset));
    return len >= 1 && len <= size - offset - 4;
}

template <class T> int safe_decode(T *msg, const void *buf, int size)
{
    try {
        return msg->decode(buf, 0, size);
    } catch (const std::exception &) {
        return -1;
    }
}

} // namespace qrt
