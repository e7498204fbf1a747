// Which LCM messages may change what the arm does (docs/security.md).
//
// A trusted sender publishes an authenticated_message_t: the encoded
// message, the channel, the sender's key name, a counter and a random
// nonce, and a message authentication code (MAC) over all of them made with
// the sender's secret key (libsodium's XChaCha20-Poly1305 with no
// plaintext). The daemon acts on a message only if the MAC verifies with
// the key of that name in --keys, the key's role may send on this channel,
// and the counter is greater than the last one accepted from that sender
// (and than the daemon's start time, so that bytes captured before a
// restart are not taken after it). Unsigned messages (no MAC) are taken only
// where the operator allowed them (planning only without keys, or
// --insecure-lcm).
#pragma once

#include <array>
#include <cstdint>
#include <map>
#include <string>
#include <vector>

#include "keyfile.hpp"

namespace qrt
{

enum class AuthRefusal {
    unsigned_message, // no signature, and unsigned input is not allowed
    malformed,        // an authenticated message that does not parse
    unknown_sender,   // no key of that name in --keys
    bad_mac,          // another key, or a byte changed after signing
    replayed,         // counter not greater than the last, or other channel
    counter_ahead,    // counter further ahead of this clock than the skew
    not_permitted,    // the key's role may not send this
};
constexpr size_t kAuthRefusals = 7;
const char *refusal_name(AuthRefusal r);

struct OpenedMessage {
    const uint8_t *payload = nullptr; // inside the received buffer
    int payload_size = 0;
    const SenderKey *sender = nullptr; // null: unsigned (allowed)
};

// The parts of an encoded authenticated_message_t, checked against its length:
// false for a buffer that is not one (another type, truncated, trailing
// bytes, lengths that lie). The payload and signed bytes stay in data.
struct AuthenticatedParts {
    std::string channel, sender_id;
    int64_t counter = 0;
    const uint8_t *payload = nullptr;
    int payload_size = 0;
    const uint8_t *nonce = nullptr; // 24 bytes
    const uint8_t *mac = nullptr;   // 16 bytes
    size_t mac_data_bytes = 0; // data[0, mac_data_bytes) is what the MAC covers
};
bool is_authenticated_message(const uint8_t *data, size_t size);
bool parse_authenticated_message(const uint8_t *data, size_t size,
                                 AuthenticatedParts *out, std::string *why);

class Authenticator
{
  public:
    // keys: the trusted senders; accept_unsigned: take unsigned messages
    // too; floor_us: counters at or below it are refused (the daemon's
    // start, CLOCK_REALTIME us); max_ahead_us: how far a counter may run
    // ahead of the daemon's clock.
    Authenticator(std::vector<SenderKey> keys, bool accept_unsigned,
                  int64_t floor_us, int64_t max_ahead_us);

    // The message to act on, or false with the refusal and a sentence.
    // Called from one thread only (the LCM thread): the counters are its.
    bool open(const std::string &channel, const uint8_t *data, size_t size,
              SenderRole needed, int64_t wall_us, OpenedMessage *out,
              AuthRefusal *refusal, std::string *why);

    bool accepts_unsigned() const
    {
        return accept_unsigned_;
    }
    size_t key_count() const
    {
        return keys_.size();
    }

  private:
    std::vector<SenderKey> keys_;
    std::map<std::string, int64_t> last_counter_; // by key name
    bool accept_unsigned_;
    int64_t floor_us_, max_ahead_us_;
};

} // namespace qrt
