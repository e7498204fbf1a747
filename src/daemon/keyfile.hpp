// Key files of the senders that may change what the arm does
// (docs/security.md): NAME.key holds a sender's name, role and secret key
// (32 bytes, hex). One copy stays with the sender, one goes into the
// daemon's --keys directory. Text, owner-only (mode 0600).
#pragma once

#include <cstdint>
#include <string>
#include <vector>

namespace qrt
{

// What a sender may publish; the daemon's copy of NAME.key decides it, not
// the message.
enum class SenderRole {
    operator_, // plan requests
    sensor,    // range scans whose sensor_id is the key's name
    joints,    // joint states (the drives' publisher, without --can)
};

const char *role_name(SenderRole role);
bool parse_role(const std::string &text, SenderRole *role);

struct SenderKey {
    std::string name; // 1..64 of A-Z a-z 0-9 _ - . (a sensor's: its id)
    SenderRole role = SenderRole::operator_;
    uint8_t key[32] = {};
};

// A key name as a file name and a sensor id both take it.
bool key_name_ok(const std::string &name);

// Writes a new key to DIR/NAME.key (never over an existing file), mode 0600,
// making DIR (mode 0700) if it does not exist. False with *why on any
// failure (nothing half-written is left).
bool generate_key(const std::string &dir, const std::string &name,
                  SenderRole role, std::string *why);

// Reads every NAME.key in dir. Refuses (false, *why) a directory or key file
// that others may write or read, or that another user owns, a malformed
// file, a name unlike its file's, and more than kMaxKeys keys.
constexpr size_t kMaxKeys = 64;
bool load_keys(const std::string &dir, std::vector<SenderKey> *keys,
               std::string *why);

} // namespace qrt
