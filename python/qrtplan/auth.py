"""Authenticating LCM messages for qrtpland (docs/security.md), with PyNaCl.

A sender's key file NAME.key (made by `qrtpland --gen-key NAME`; the daemon
holds a copy in its --keys directory) holds the sender's name, role and
secret key. Signer.seal(channel, payload) wraps an encoded message in a
qrtplan.authenticated_message_t: the channel, the key's name, a counter
that grows with every message (this computer's CLOCK_REALTIME in
microseconds, made strictly greater than the last), a random nonce, and a
MAC of every byte before it: libsodium's XChaCha20-Poly1305 with no
plaintext, those bytes as associated data. The message types are the
package's (qrtplan.lcmtypes), or lcm-gen's top-level qrtplan when this file
is loaded outside the package (tools/qrtauth.py, with build/lcmtypes/python
on sys.path). This is the one home of the signing code.
"""
from __future__ import annotations

import os
import stat
import struct
import threading
import time

import nacl.bindings
import nacl.utils

try:
    from .lcmtypes import authenticated_message_t
except ImportError:  # loaded by tools/qrtauth.py, outside the package
    from qrtplan import authenticated_message_t


# the type's fingerprint, as its encode() writes it first
_FINGERPRINT = authenticated_message_t._get_packed_fingerprint()


__all__ = ["KeyFileError", "Signer", "SignedPublisher", "scan_sensor_id", "gen_keys"]


class KeyFileError(Exception):
    """A key file that cannot be used (unreadable, shared, malformed)."""


def _fields(path, words):
    """The `word value` lines of a key file, refusing one that others may
    read or change (as the daemon does)."""
    fd = os.open(path, os.O_RDONLY | os.O_NOFOLLOW | os.O_NONBLOCK)
    try:
        st = os.fstat(fd)
        if not stat.S_ISREG(st.st_mode):
            raise KeyFileError(f"{path}: not a regular file")
        if st.st_uid != os.geteuid() or st.st_mode & 0o077:
            raise KeyFileError(f"{path}: mode {stat.S_IMODE(st.st_mode):04o} or "
                               "owner lets other users read or change it")
        text = os.read(fd, 4097).decode("ascii", "replace")
    finally:
        os.close(fd)
    got = {}
    for line in text.splitlines():
        if line and not line.startswith("#"):
            word, _, value = line.partition(" ")
            got[word] = value
    missing = [w for w in words if not got.get(w)]
    if missing:
        raise KeyFileError(f"{path}: no {', '.join(missing)} line")
    return got


class Signer:
    """One sender: its name, role and secret key."""

    def __init__(self, path):
        f = _fields(path, ("name", "role", "secret"))
        self.name, self.role = f["name"], f["role"]
        try:
            key = bytes.fromhex(f["secret"])
        except ValueError:
            key = b""
        if len(key) != 32:
            raise KeyFileError(f"{path}: secret: want 64 hex digits")
        self._key = key
        self._last = 0
        self._lock = threading.Lock()

    def counter(self):
        with self._lock:
            self._last = max(self._last + 1, time.time_ns() // 1000)
            return self._last

    def seal(self, channel, payload, counter=None):
        """The authenticated_message_t carrying payload, encoded. Written
        field by field rather than with the generated encode(), which copies
        the payload four times (a 173 KB scan: 80 us here)."""
        counter = self.counter() if counter is None else counter
        nonce = nacl.utils.random(24)

        def lcm_string(text):
            raw = text.encode() + b"\0"
            return struct.pack(">i", len(raw)) + raw
        data = b"".join((_FINGERPRINT, lcm_string(channel), lcm_string(self.name),
                         struct.pack(">qi", counter, len(payload)), payload, nonce))
        return data + nacl.bindings.crypto_aead_xchacha20poly1305_ietf_encrypt(
            b"", data, nonce, self._key)


def scan_sensor_id(data):
    """The sensor_id of an encoded range_scan_t or point_cloud_t (both:
    fingerprint 8, utime 8, then the string), without decoding the
    returns or points."""
    (n,) = struct.unpack_from(">i", data, 16)
    return data[20:20 + n - 1].decode("utf-8", "replace")


class SignedPublisher:
    """Publishes as the daemon's trusted senders do: a request with the
    operator key, a scan or a cloud (on the scan or cloud channel, or its
    NAME_* channels) with the key named by its sensor_id, a joint state with
    the joints key. `signers` are Signer objects; the channels are the
    daemon's defaults unless given."""

    def __init__(self, lc, signers, request_channel="QRT_PLAN_REQUEST",
                 scan_channel="QRT_SCAN", joint_channel="QRT_JOINT_STATE",
                 cloud_channel="QRT_CLOUD"):
        self.lc = lc
        self.by_name = {s.name: s for s in signers}
        self.by_role = {}
        for s in signers:
            self.by_role.setdefault(s.role, s)
        self.channels = (request_channel, scan_channel, joint_channel, cloud_channel)

    def signer_for(self, channel, data):
        req, scan, joints, cloud = self.channels
        if channel == req:
            return self.by_role["operator"]
        if any(channel == c or channel.startswith(c + "_") for c in (scan, cloud)):
            return self.by_name[scan_sensor_id(data)]
        if channel == joints:
            return self.by_role["joints"]
        raise KeyError(f"no signer for channel {channel}")

    def publish(self, channel, data):
        if not isinstance(data, (bytes, bytearray)):
            data = data.encode()
        self.lc.publish(channel, self.signer_for(channel, data).seal(channel, data))


def gen_keys(daemon_bin, key_dir, names_roles):
    """Keys for tests and demos, made by the daemon's own --gen-key (the
    sender and the daemon share key_dir here)."""
    import subprocess
    os.makedirs(key_dir, mode=0o700, exist_ok=True)
    for name, role in names_roles:
        if not os.path.exists(os.path.join(key_dir, name + ".key")):
            subprocess.run([daemon_bin, "--gen-key", name, "--role", role,
                            "--key-dir", key_dir], check=True,
                           stdout=subprocess.DEVNULL)
    return [Signer(os.path.join(key_dir, n + ".key")) for n, _ in names_roles]
