#include "keyfile.hpp"

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <dirent.h>
#include <fcntl.h>
#include <sodium.h>
#include <sys/stat.h>
#include <unistd.h>

namespace qrt
{

const char *role_name(SenderRole role)
{
    switch (role) {
    case SenderRole::operator_:
        return "operator";
    case SenderRole::sensor:
        return "sensor";
    case SenderRole::joints:
        return "joints";
    }
    return "?";
}

bool parse_role(const std::string &text, SenderRole *role)
{
    for (SenderRole r :
         {SenderRole::operator_, SenderRole::sensor, SenderRole::joints})
        if (text == role_name(r)) {
            *role = r;
            return true;
        }
    return false;
}

bool key_name_ok(const std::string &name)
{
    if (name.empty() || name.size() > 64 || name[0] == '.')
        return false;
    for (char c : name)
        if (!std::isalnum(static_cast<unsigned char>(c)) && c != '_' &&
            c != '-' && c != '.')
            return false;
    return true;
}

namespace
{

constexpr size_t kMaxKeyFileBytes = 4096;

// Who may read or change a key file or the directory of trusted keys: its
// owner, who must be this process's user. Group or world bits would let
// another account read a seed, or plant or edit a trusted key.
bool owner_only(const struct stat &st, const std::string &path,
                mode_t allowed_other_bits, std::string *why)
{
    if (st.st_uid != geteuid()) {
        *why = path + ": owned by uid " + std::to_string(st.st_uid) +
               ", not by this user (uid " + std::to_string(geteuid()) + ")";
        return false;
    }
    if ((st.st_mode & 077 & ~allowed_other_bits) != 0) {
        char mode[8];
        std::snprintf(mode, sizeof mode, "%04o", unsigned(st.st_mode & 07777));
        *why = path + ": mode " + mode +
               " lets other users read or change it; chmod go-rwx it";
        return false;
    }
    return true;
}

bool read_small_file(const std::string &path, std::string *text,
                     std::string *why)
{
    int fd = open(path.c_str(), O_RDONLY | O_NOFOLLOW | O_NONBLOCK | O_CLOEXEC);
    if (fd < 0) {
        *why = path + ": cannot open: " + std::strerror(errno);
        return false;
    }
    struct stat st {
    };
    bool ok = fstat(fd, &st) == 0;
    if (!ok)
        *why = path + ": cannot stat: " + std::strerror(errno);
    else if (!S_ISREG(st.st_mode)) {
        *why = path + ": not a regular file";
        ok = false;
    } else if (!owner_only(st, path, 0, why))
        ok = false;
    else if (size_t(st.st_size) > kMaxKeyFileBytes) {
        *why = path + ": over " + std::to_string(kMaxKeyFileBytes) +
               " bytes, not a key file";
        ok = false;
    }
    if (ok) {
        char buf[kMaxKeyFileBytes + 1];
        ssize_t n = read(fd, buf, sizeof buf);
        if (n < 0 || size_t(n) > kMaxKeyFileBytes) {
            *why = path + ": cannot read it whole";
            ok = false;
        } else
            text->assign(buf, size_t(n));
        sodium_memzero(buf, sizeof buf); // a secret key: no copies left
    }
    close(fd);
    return ok;
}

// "word value" lines; '#' starts a comment line. Each word once.
bool parse_fields(const std::string &text, const std::string &path,
                  std::vector<std::pair<std::string, std::string>> *fields,
                  std::string *why)
{
    size_t from = 0;
    int lineno = 0;
    while (from < text.size()) {
        size_t nl = text.find('\n', from);
        std::string line = text.substr(
            from, nl == std::string::npos ? std::string::npos : nl - from);
        from = nl == std::string::npos ? text.size() : nl + 1;
        lineno++;
        if (line.empty() || line[0] == '#')
            continue;
        size_t sp = line.find(' ');
        std::string word = line.substr(0, sp);
        std::string value =
            sp == std::string::npos ? std::string() : line.substr(sp + 1);
        for (auto &f : *fields)
            if (f.first == word && !f.second.empty()) {
                *why = path + ":" + std::to_string(lineno) + ": " + word +
                       " given twice";
                return false;
            }
        bool known = false;
        for (auto &f : *fields)
            if (f.first == word) {
                f.second = value;
                known = true;
            }
        if (!known || value.empty()) {
            *why = path + ":" + std::to_string(lineno) +
                   ": want one of the lines name, role and the key";
            return false;
        }
    }
    for (auto &f : *fields)
        if (f.second.empty()) {
            *why = path + ": no " + f.first + " line";
            return false;
        }
    return true;
}

bool write_new_file(const std::string &path, const std::string &text,
                    std::string *why)
{
    int fd = open(path.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC, 0600);
    if (fd < 0) {
        *why = path + ": cannot create: " + std::strerror(errno);
        return false;
    }
    bool ok = fchmod(fd, 0600) == 0 && // whatever the umask
              write(fd, text.data(), text.size()) == ssize_t(text.size()) &&
              fsync(fd) == 0;
    if (!ok)
        *why = path + ": cannot write: " + std::strerror(errno);
    if (close(fd) != 0 && ok) {
        *why = path + ": cannot write: " + std::strerror(errno);
        ok = false;
    }
    if (!ok)
        unlink(path.c_str());
    return ok;
}

std::string hex(const uint8_t *bytes, size_t n)
{
    std::string out(2 * n + 1, '\0');
    sodium_bin2hex(&out[0], out.size(), bytes, n);
    out.pop_back();
    return out;
}

} // namespace

bool generate_key(const std::string &dir, const std::string &name,
                  SenderRole role, std::string *why)
{
    if (!key_name_ok(name)) {
        *why = "key name '" + name +
               "': want 1..64 of A-Z a-z 0-9 _ - . (not starting with .)";
        return false;
    }
    if (sodium_init() < 0) {
        *why = "libsodium failed to start";
        return false;
    }
    uint8_t key[crypto_aead_xchacha20poly1305_ietf_KEYBYTES];
    crypto_aead_xchacha20poly1305_ietf_keygen(key);
    std::string text = "# qrtplan sender key: one copy with the sender, one "
                       "in qrtpland's --keys DIR; owner-only\nname " +
                       name + "\nrole " + role_name(role) + "\nsecret " +
                       hex(key, sizeof key) + "\n";
    sodium_memzero(key, sizeof key);
    std::string d = dir.empty() ? std::string(".") : dir;
    // a new directory is owner-only, as load_keys wants it
    if (mkdir(d.c_str(), 0700) != 0 && errno != EEXIST) {
        *why = d + ": cannot create: " + std::strerror(errno);
        sodium_memzero(&text[0], text.size());
        return false;
    }
    bool ok = write_new_file(d + "/" + name + ".key", text, why);
    sodium_memzero(&text[0], text.size());
    return ok;
}

bool load_keys(const std::string &dir, std::vector<SenderKey> *keys,
               std::string *why)
{
    keys->clear();
    struct stat st {
    };
    if (stat(dir.c_str(), &st) != 0 || !S_ISDIR(st.st_mode)) {
        *why = dir + ": not a directory";
        return false;
    }
    // others may list and enter the directory (r-x), never add to it
    if (!owner_only(st, dir, 055, why))
        return false;
    DIR *d = opendir(dir.c_str());
    if (!d) {
        *why = dir + ": cannot open: " + std::strerror(errno);
        return false;
    }
    std::vector<std::string> names;
    while (struct dirent *e = readdir(d)) {
        std::string f = e->d_name;
        if (f.size() > 4 && f.compare(f.size() - 4, 4, ".key") == 0)
            names.push_back(f);
    }
    closedir(d);
    std::sort(names.begin(), names.end());
    if (names.empty()) {
        *why = dir + ": no NAME.key files (qrtpland --gen-key NAME)";
        return false;
    }
    if (names.size() > kMaxKeys) {
        *why = dir + ": " + std::to_string(names.size()) + " keys, over " +
               std::to_string(kMaxKeys);
        return false;
    }
    for (const std::string &f : names) {
        std::string path = dir + "/" + f, text;
        if (!read_small_file(path, &text, why))
            return false;
        std::vector<std::pair<std::string, std::string>> fields = {
            {"name", ""}, {"role", ""}, {"secret", ""}};
        if (!parse_fields(text, path, &fields, why))
            return false;
        SenderKey k;
        k.name = fields[0].second;
        if (!key_name_ok(k.name) || k.name + ".key" != f) {
            *why = path + ": name '" + k.name + "' is not the file's name";
            return false;
        }
        if (!parse_role(fields[1].second, &k.role)) {
            *why = path + ": role '" + fields[1].second +
                   "': want operator, sensor or joints";
            return false;
        }
        size_t got = 0;
        std::string &h = fields[2].second;
        if (h.size() != 2 * sizeof k.key ||
            sodium_hex2bin(k.key, sizeof k.key, h.data(), h.size(), nullptr,
                           &got, nullptr) != 0 ||
            got != sizeof k.key) {
            *why = path + ": secret: want 64 hex digits";
            return false;
        }
        sodium_memzero(&h[0], h.size());
        sodium_memzero(&text[0], text.size());
        keys->push_back(k);
    }
    return true;
}

} // namespace qrt
