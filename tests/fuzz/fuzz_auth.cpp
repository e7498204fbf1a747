// libFuzzer target on qrtpland's authenticated-message decoder
// (src/daemon/auth.cpp): any bytes, from any channel, for any role. Seeds
// are messages authenticated with the fixed test keys below
// (tools/fuzz_lcm.sh writes them), so that the fuzzer reaches the paths
// behind a valid MAC too.
//
// Checked: nothing crashes or reads outside the input; what is accepted is
// a payload inside the input from a known sender whose role the channel
// takes; and an accepted message with any one byte changed is refused.
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <sodium.h>
#include <vector>

#include "auth.hpp"

namespace
{

std::vector<qrt::SenderKey> test_keys()
{
    std::vector<qrt::SenderKey> keys(2);
    keys[0].name = "op";
    keys[0].role = qrt::SenderRole::operator_;
    keys[1].name = "s0";
    keys[1].role = qrt::SenderRole::sensor;
    for (int i = 0; i < 32; i++) {
        keys[0].key[i] = uint8_t(i);      // tools/fuzz_lcm.sh: 000102...1f
        keys[1].key[i] = uint8_t(32 + i); // 202122...3f
    }
    return keys;
}

// far from the clock's edges: every seed's counter is inside
constexpr int64_t kFloor = 1000, kNow = int64_t(1) << 60;

// Opened by a fresh authenticator; an accepted message is checked here,
// while the sender it points to lives.
bool open_fresh(const std::vector<uint8_t> &msg, const std::string &channel,
                qrt::SenderRole role)
{
    qrt::Authenticator auth(test_keys(), false, kFloor, 0);
    qrt::AuthRefusal why{};
    std::string text;
    qrt::OpenedMessage out;
    if (!auth.open(channel, msg.data(), msg.size(), role, kNow, &out, &why,
                   &text))
        return false;
    if (!out.sender || out.sender->role != role || out.payload_size < 0 ||
        out.payload < msg.data() ||
        out.payload + out.payload_size > msg.data() + msg.size())
        __builtin_trap();
    return true;
}

} // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    static bool started = sodium_init() >= 0;
    if (!started || size > (1u << 20) || size < 1)
        return 0;
    // the first byte picks the channel and role the message arrives on
    static const char *const channels[] = {"QRT_PLAN_REQUEST", "QRT_SCAN"};
    const qrt::SenderRole roles[] = {qrt::SenderRole::operator_,
                                     qrt::SenderRole::sensor};
    const int pick = data[0] & 1;
    data++;
    size--;
    // an owned copy: the decoder must not read past the end
    std::vector<uint8_t> msg(data, data + size);
    if (!open_fresh(msg, channels[pick], roles[pick]))
        return 0;
    // tamper: a single-byte change anywhere is refused (the MAC covers
    // all); 64 places spread over the message, its first and last byte
    std::vector<size_t> places;
    for (size_t i = 0; i < msg.size(); i += msg.size() / 64 + 1)
        places.push_back(i);
    places.push_back(msg.size() - 1);
    for (size_t i : places) {
        std::vector<uint8_t> t = msg;
        t[i] ^= uint8_t(1 + (data[i % size] & 0x7f));
        if (open_fresh(t, channels[pick], roles[pick]))
            __builtin_trap();
    }
    // the same bytes twice to one authenticator: the second is a replay
    qrt::Authenticator auth(test_keys(), false, kFloor, 0);
    qrt::AuthRefusal why{};
    std::string text;
    qrt::OpenedMessage out;
    if (!auth.open(channels[pick], msg.data(), msg.size(), roles[pick], kNow,
                   &out, &why, &text) ||
        auth.open(channels[pick], msg.data(), msg.size(), roles[pick], kNow,
                  &out, &why, &text) ||
        why != qrt::AuthRefusal::replayed)
        __builtin_trap();
    return 0;
}
