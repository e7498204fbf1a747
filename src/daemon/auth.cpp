#include "auth.hpp"

#include <sodium.h>

#include "decode.hpp"
#include "qrtplan/authenticated_message_t.hpp"

namespace qrt
{

const char *refusal_name(AuthRefusal r)
{
    static const char *const names[kAuthRefusals] = {
        "unsigned", "malformed",     "unknown sender", "bad MAC",
        "replayed", "counter ahead", "not permitted"};
    return names[size_t(r)];
}

namespace
{

// An LCM string at *pos: int32 length counting the NUL, the bytes, the NUL;
// at most max_chars characters and no NUL inside.
bool take_string(const uint8_t *data, size_t size, size_t *pos,
                 size_t max_chars, std::string *out)
{
    if (size - *pos < 4)
        return false;
    uint32_t len = lcm_u32(data + *pos);
    if (len < 1 || len - 1 > max_chars || len > size - *pos - 4)
        return false;
    const char *s = reinterpret_cast<const char *>(data + *pos + 4);
    if (s[len - 1] != '\0' || std::char_traits<char>::find(s, len - 1, '\0'))
        return false;
    out->assign(s, len - 1);
    *pos += 4 + len;
    return true;
}

} // namespace

bool is_authenticated_message(const uint8_t *data, size_t size)
{
    return size >= 8 &&
           lcm_u64(data) ==
               uint64_t(qrtplan::authenticated_message_t::getHash());
}

bool parse_authenticated_message(const uint8_t *data, size_t size,
                                 AuthenticatedParts *out, std::string *why)
{
    constexpr size_t kNonce = crypto_aead_xchacha20poly1305_ietf_NPUBBYTES;
    constexpr size_t kMac = crypto_aead_xchacha20poly1305_ietf_ABYTES;
    constexpr size_t kSig = kNonce + kMac;
    size_t pos = 8;
    if (!is_authenticated_message(data, size)) {
        *why = "not a qrtplan.authenticated_message_t";
        return false;
    }
    if (!take_string(data, size, &pos, 63, &out->channel) ||
        !take_string(data, size, &pos, 64, &out->sender_id)) {
        *why = "channel or sender_id malformed";
        return false;
    }
    if (size - pos < 12) {
        *why = "truncated before the payload";
        return false;
    }
    out->counter = int64_t(lcm_u64(data + pos));
    int32_t n = int32_t(lcm_u32(data + pos + 8));
    pos += 12;
    // exactly the payload, the nonce and the MAC remain: nothing
    // unauthenticated may ride along after it
    if (n < 0 || size - pos < kSig || size_t(n) != size - pos - kSig) {
        *why = "payload_size " + std::to_string(n) + " does not match the " +
               std::to_string(size) + " bytes received";
        return false;
    }
    out->payload = data + pos;
    out->payload_size = n;
    out->nonce = data + pos + size_t(n);
    out->mac_data_bytes = pos + size_t(n) + kNonce;
    out->mac = data + out->mac_data_bytes;
    return true;
}

Authenticator::Authenticator(std::vector<SenderKey> keys, bool accept_unsigned,
                             int64_t floor_us, int64_t max_ahead_us)
    : keys_(std::move(keys)), accept_unsigned_(accept_unsigned),
      floor_us_(floor_us), max_ahead_us_(max_ahead_us)
{
}

bool Authenticator::open(const std::string &channel, const uint8_t *data,
                         size_t size, SenderRole needed, int64_t wall_us,
                         OpenedMessage *out, AuthRefusal *refusal,
                         std::string *why)
{
    auto refuse = [&](AuthRefusal r, std::string text) {
        *refusal = r;
        *why = std::move(text);
        return false;
    };
    if (!is_authenticated_message(data, size)) {
        if (!accept_unsigned_)
            return refuse(AuthRefusal::unsigned_message,
                          "unsigned message (this daemon takes only "
                          "messages authenticated with a key in --keys)");
        out->payload = data;
        out->payload_size = int(size);
        out->sender = nullptr;
        return true;
    }
    AuthenticatedParts m;
    std::string detail;
    if (!parse_authenticated_message(data, size, &m, &detail))
        return refuse(AuthRefusal::malformed,
                      "authenticated message: " + detail);
    const SenderKey *key = nullptr;
    for (const SenderKey &k : keys_)
        if (k.name == m.sender_id)
            key = &k;
    if (!key)
        return refuse(AuthRefusal::unknown_sender,
                      "sender '" + m.sender_id + "' has no key in --keys");
    // an AEAD with no plaintext: the tag authenticates the associated data,
    // every byte before it (libsodium, Poly1305 keyed per nonce)
    uint8_t none[1] = {0};
    if (crypto_aead_xchacha20poly1305_ietf_decrypt_detached(
            none, nullptr, none, 0, m.mac, data, m.mac_data_bytes, m.nonce,
            key->key) != 0)
        return refuse(AuthRefusal::bad_mac,
                      "MAC of '" + m.sender_id +
                          "' does not verify (another key, or changed)");
    // authentic from here on: what it says of itself can be believed
    if (m.channel != channel)
        return refuse(AuthRefusal::replayed, "'" + m.sender_id +
                                                 "' signed it for channel " +
                                                 m.channel);
    if (key->role != needed)
        return refuse(AuthRefusal::not_permitted,
                      "'" + m.sender_id + "' is a " + role_name(key->role) +
                          " key; this channel takes " + role_name(needed) +
                          " keys");
    if (m.counter > wall_us + max_ahead_us_)
        return refuse(AuthRefusal::counter_ahead,
                      "counter of '" + m.sender_id + "' is " +
                          std::to_string((m.counter - wall_us) / 1000) +
                          " ms ahead of this computer's clock");
    auto last = last_counter_.find(key->name);
    int64_t floor = last == last_counter_.end() ? floor_us_ : last->second;
    if (m.counter <= floor)
        return refuse(AuthRefusal::replayed,
                      "counter of '" + m.sender_id + "' did not grow (" +
                          std::to_string(m.counter) +
                          (last == last_counter_.end()
                               ? " is before this daemon started)"
                               : " after " + std::to_string(floor) + ")"));
    last_counter_[key->name] = m.counter;
    out->payload = m.payload;
    out->payload_size = m.payload_size;
    out->sender = key;
    return true;
}

} // namespace qrt
