"""qrtplan plan's memory is bounded by its budget, --max-memory BYTES
(default 1 GiB), whatever the input: a cloud that expands fiftyfold, a
header that lies about its size or whose size product overflows, /dev/zero,
a FIFO or a directory as the points_file, a large inline JSON scene. Each
run is measured alone (os.wait4 in a small launcher gives its own peak
resident set) under a timeout (a hang fails the test); each input is
planned within the budget or refused with exit 2 and one line on stderr."""
import json
import os
import signal
import struct
import subprocess
import sys
import tempfile
import time

import lzf
import numpy as np
import pytest

from conftest import BIN, max_points

MiB = 1 << 20
START_GOAL = {"start": {"joints_deg": [-100, 0, 0]},
              "goal": {"joints_deg": [100, 0, 0]}}


class Run:
    def __init__(self, rc, out, err, rss, seconds):
        self.rc, self.out, self.err = rc, out, err
        self.rss, self.seconds = rss, seconds

    def __repr__(self):
        return (f"exit {self.rc}, peak RSS {self.rss / MiB:.1f} MiB, "
                f"{self.seconds:.2f} s, stderr {self.err[:300]!r}")


# A small process runs qrtplan and reports its peak RSS: a child forked
# (or vforked) by pytest itself would count pytest's own pages, hundreds of
# MB after the big clouds here, as its peak.
LAUNCHER = r"""
import os, sys
pid = os.fork()
if pid == 0:
    os.execv(sys.argv[2], sys.argv[2:])
_, status, usage = os.wait4(pid, 0)
with open(sys.argv[1], "w") as f:
    f.write(str(usage.ru_maxrss * 1024))
code = os.waitstatus_to_exitcode(status)
sys.exit(code if code >= 0 else 128 - code)
"""


ENV = dict(os.environ)
if "ASAN_OPTIONS" in ENV:
    # ASan keeps freed memory in quarantine (256 MiB): without it the peak
    # measures the sanitizer, not qrtplan
    ENV["ASAN_OPTIONS"] += ":quarantine_size_mb=0"


def measure(args, timeout=10, stdin=subprocess.DEVNULL):
    """Run qrtplan; its exit status, output, peak RSS (bytes) and time."""
    with tempfile.TemporaryDirectory() as tmp:
        rss = os.path.join(tmp, "rss")
        with open(os.path.join(tmp, "out"), "w+b") as out, \
                open(os.path.join(tmp, "err"), "w+b") as err:
            t0 = time.monotonic()
            p = subprocess.Popen([sys.executable, "-S", "-c", LAUNCHER, rss,
                                  str(BIN), *map(str, args)], stdin=stdin,
                                 stdout=out, stderr=err, env=ENV,
                                 start_new_session=True)
            try:
                p.wait(timeout)
            except subprocess.TimeoutExpired:
                os.killpg(p.pid, signal.SIGKILL)
                p.wait()
                pytest.fail(f"qrtplan {args} still running after {timeout} s")
            seconds = time.monotonic() - t0
            out.seek(0)
            err.seek(0)
            with open(rss) as f:
                peak = int(f.read())
            return Run(p.returncode, out.read().decode(), err.read().decode(),
                       peak, seconds)


def refused(r, *words):
    """Exit 2 and one line naming the problem."""
    assert r.rc == 2, r
    lines = r.err.splitlines()
    assert len(lines) == 1 and lines[0].startswith("qrtplan: "), r
    for w in words:
        assert w in lines[0], r
    return lines[0]


def planned(r):
    assert r.rc == 0, r
    plan = json.loads(r.out)
    del plan["stats"]["time_us"]
    return plan


_least = []


def least_budget():
    """The least --max-memory this build takes, in MiB, as its refusal of
    a smaller one says: the planner's state (which grows with the build's
    QRT_MAX_POINTS) and the program."""
    if not _least:
        r = measure(["plan", "scene.json", "--max-memory", "1M"])
        line = refused(r, "--max-memory", "at least")
        _least.append(int(line.split("at least ")[1].split(" MiB")[0]))
    return _least[0]


def scene_file(tmp_path, name="scene.json", **fields):
    path = tmp_path / name
    path.write_text(json.dumps({"version": 1, **fields, **START_GOAL}))
    return path


def pcd_header(n, data, width=None, height=1, fields="x y z", size="4 4 4",
               type_="F F F", count="1 1 1"):
    points = "" if n is None else f"POINTS {n}\n"
    return (f"VERSION 0.7\nFIELDS {fields}\nSIZE {size}\nTYPE {type_}\n"
            f"COUNT {count}\nWIDTH {n if width is None else width}\n"
            f"HEIGHT {height}\nVIEWPOINT 0 0 0 1 0 0 0\n{points}"
            f"DATA {data}\n").encode()


def compressed_pcd(columns):
    """A binary_compressed PCD of float32 x, y and z columns, compressed by
    liblzf."""
    soa = b"".join(np.asarray(c, np.float32).tobytes() for c in columns)
    packed = lzf.compress(soa, len(soa))
    assert packed is not None
    return (pcd_header(len(columns[0]), "binary_compressed") +
            struct.pack("<II", len(packed), len(soa)) + packed)


# --- points_file that is not a file --------------------------------------

@pytest.mark.parametrize("kind", ["fifo", "/dev/zero", "directory"])
def test_points_file_that_is_not_a_regular_file_is_refused_at_once(
        qrtplan, tmp_path, kind):
    """A FIFO used to block for ever (nothing writes it), /dev/zero was
    read to 1 GiB before it was refused, a directory gave 'cannot read'."""
    if kind == "fifo":
        os.mkfifo(tmp_path / "cloud.pcd")
        name = "cloud.pcd"
    elif kind == "directory":
        (tmp_path / "cloud.pcd").mkdir()
        name = "cloud.pcd"
    else:
        name = kind
    r = measure(["plan", scene_file(tmp_path, points_file=name)], timeout=10)
    refused(r, name, "not a regular file")
    assert r.seconds < 5 and r.rss < 64 * MiB, r


def test_dev_zero_as_the_scene_is_refused_at_once(qrtplan):
    r = measure(["plan", "/dev/zero"])
    refused(r, "/dev/zero", "not a regular file")
    assert r.seconds < 5 and r.rss < 64 * MiB, r


def test_endless_pipe_as_the_scene_stops_at_the_budget(qrtplan):
    """A pipe may be a scene ('-', or <(...)): what it holds is read only as
    far as the budget allows. A device as standard input is refused as a
    named one is."""
    producer = subprocess.Popen(["cat", "/dev/zero"], stdout=subprocess.PIPE)
    try:
        r = measure(["plan", "-", "--max-memory", "48M"],
                    stdin=producer.stdout)
    finally:
        producer.kill()
        producer.wait()
        producer.stdout.close()
    refused(r, "standard input", "memory budget", "48 MiB", "--max-memory")
    assert r.rss < 48 * MiB, r
    with open("/dev/zero", "rb") as zero:
        r = measure(["plan", "-"], stdin=zero)
    refused(r, "standard input", "not a regular file or a pipe")
    assert r.seconds < 5 and r.rss < 64 * MiB, r


# --- PCD files that expand or lie ----------------------------------------

def test_large_binary_compressed_cloud_is_planned_within_the_budget(
        qrtplan, tmp_path):
    """20 million points (240 MB of x y z) in 5 MB of LZF. It used to be
    expanded whole, then copied twice as doubles (4.2 GB for a 12 MB file);
    now it is decoded as it is read, straight into the planner's table."""
    rng = np.random.default_rng(35)
    pattern = (rng.uniform(-0.5, 0.5, (1000, 3)) + [0.0, -0.6, 0.3]).astype(
        np.float32)
    (tmp_path / "cloud.pcd").write_bytes(compressed_pcd(
        [np.tile(pattern[:, k], 20_000) for k in range(3)]))
    s = scene_file(tmp_path, points_file="cloud.pcd")
    default = measure(["plan", s], timeout=30)
    plan = planned(default)
    assert plan["stats"]["voxel_m"] > 0 and plan["stats"]["points"] <= 1000
    assert default.rss < 64 * MiB, default
    least = least_budget()
    small = measure(["plan", s, "--max-memory", f"{least}M"], timeout=30)
    assert planned(small) == plan
    assert small.rss < least * MiB, small


def test_a_cloud_that_holds_less_than_its_header_says(qrtplan, tmp_path):
    """Sizes that agree with each other and with WIDTH, but the stream
    stops three quarters of the way: the 480 MB it claims were allocated
    and mostly written before the shortfall was found."""
    n = 40_000_000
    want = 12 * n
    # 4 literal bytes (0.6f), then back references of 264 bytes each (3
    # bytes of stream) to three quarters of the stated size, then literal
    # zeros (2 bytes of stream a byte) until the stream is long enough to
    # pass the check that LZF can reach the stated size from it
    k = (want * 3 // 4 - 4) // 264
    body = b"\x03" + struct.pack("<f", 0.6) + b"\xe0\xff\x03" * k
    body += b"\x00\x00" * ((want // 80 - len(body)) // 2 + 1)
    data = pcd_header(n, "binary_compressed") + \
        struct.pack("<II", len(body), want) + bytes(body)
    (tmp_path / "cloud.pcd").write_bytes(data)
    r = measure(["plan", scene_file(tmp_path, points_file="cloud.pcd")],
                timeout=30)
    refused(r, "cloud.pcd", "binary_compressed")
    assert r.rss < 64 * MiB, r


@pytest.mark.parametrize("data", ["binary", "binary_compressed", "ascii"])
def test_size_product_that_overflows_is_refused(qrtplan, tmp_path, data):
    """WIDTH x HEIGHT without POINTS, 2^30 x 2^30 points of 16 bytes: 2^64
    bytes, which wrapped to 0 and passed the binary reader's size check."""
    header = pcd_header(None, data, width=1 << 30, height=1 << 30,
                        fields="x y z w", size="4 4 4 4", type_="F F F F",
                        count="1 1 1 1")
    (tmp_path / "cloud.pcd").write_bytes(header + b"\0" * 64)
    r = measure(["plan", scene_file(tmp_path, points_file="cloud.pcd")])
    refused(r, "cloud.pcd", "WIDTH x HEIGHT", "1073741824")
    assert r.seconds < 5 and r.rss < 64 * MiB, r


@pytest.mark.parametrize("data", ["binary", "binary_compressed", "ascii"])
def test_two_billion_points_in_a_few_bytes(qrtplan, tmp_path, data):
    payload = pcd_header(2_000_000_000, data) + b"\0" * 64
    (tmp_path / "cloud.pcd").write_bytes(payload)
    r = measure(["plan", scene_file(tmp_path, points_file="cloud.pcd")])
    refused(r, "cloud.pcd")
    assert r.seconds < 5 and r.rss < 64 * MiB, r


# --- JSON scenes ---------------------------------------------------------

def test_large_json_scene_costs_little_more_than_its_size(qrtplan, tmp_path):
    """400,000 inline points, 15 MB of JSON: it cost 8 to 20 times its
    size as a tree; now the points array is checked, then read a point at
    a time into the planner. Refused when the file and the planner's own
    state do not fit the budget."""
    rng = np.random.default_rng(6)
    # on a 1/1024 m grid: short decimals, exact as float32
    xyz = (np.round(rng.uniform(-0.4, 0.4, (400_000, 3)) * 1024) / 1024 +
           [0.0, 0.625, 0.25]).astype(np.float32)
    pts = [[float(v) for v in p] for p in xyz]
    path = tmp_path / "scene.json"
    path.write_text(json.dumps({"version": 1, "points": pts, **START_GOAL},
                               separators=(",", ":")))
    size = path.stat().st_size
    default = measure(["plan", path], timeout=30)
    plan = planned(default)
    # exact where the build's table holds them all, else merged
    assert (plan["stats"]["voxel_m"] > 0) == (len(xyz) > max_points())
    least = least_budget()
    assert default.rss < size + least * MiB, (size, default)
    fits = measure(["plan", path, "--max-memory", f"{least + 24}M"],
                   timeout=30)
    assert planned(fits) == plan and fits.rss < (least + 24) * MiB, fits
    # the least budget this build takes (the state and the program), less
    # than the text and the state
    r = measure(["plan", path, "--max-memory", f"{least}M"])
    refused(r, "scene.json", "memory budget", f"{least} MiB", "--max-memory")
    assert r.rss < least * MiB, r
    # the same points from a binary PCD: the same plan
    (tmp_path / "cloud.pcd").write_bytes(pcd_header(len(xyz), "binary") +
                                         xyz.tobytes())
    from_pcd = measure(["plan", scene_file(tmp_path, "pcd.json",
                                           points_file="cloud.pcd")])
    assert planned(from_pcd) == plan


def test_large_value_outside_the_points_is_held_to_the_budget(qrtplan,
                                                              tmp_path):
    """Only the points array is read without a tree: a huge "comment" is
    parsed as any JSON is, and refused when its tree would pass the
    budget."""
    path = scene_file(tmp_path, points=[[0.5, 0.5, 0.5]],
                      comment=[0] * 1_000_000)
    least = least_budget()
    r = measure(["plan", path, "--max-memory", f"{least}M"])
    refused(r, "scene.json", "memory budget", "--max-memory")
    assert r.rss < least * MiB, r
    planned(measure(["plan", path]))


# --- the option ----------------------------------------------------------

@pytest.mark.parametrize("value", ["1073741824", "2G", "512M", "65536k",
                                   "64MiB", "1g"])
def test_max_memory_accepts_bytes_and_suffixes(qrtplan, tmp_path, value):
    s = scene_file(tmp_path, points=[[0.5, 0.5, 0.5]])
    planned(measure(["plan", s, "--max-memory", value]))
    planned(measure(["plan", "--max-memory", value, s]))
    r = measure(["mask", s, "--max-memory", value])
    assert r.rc == 0 and json.loads(r.out)["blocked"], r


@pytest.mark.parametrize("value,words", [
    ("abc", ["--max-memory"]), ("", ["--max-memory"]), ("-5M", ["--max-memory"]),
    ("12Q", ["--max-memory"]), ("1.5G", ["--max-memory"]),
    ("99999999999999999999", ["--max-memory"]),
    ("4M", ["--max-memory", "at least"]),
])
def test_max_memory_refuses_bad_values(qrtplan, tmp_path, value, words):
    s = scene_file(tmp_path, points=[[0.5, 0.5, 0.5]])
    refused(measure(["plan", s, "--max-memory", value]), *words)


@pytest.mark.parametrize("command", ["plan", "mask"])
def test_help_documents_the_budget(qrtplan, command):
    r = measure([command, "--help"])
    assert r.rc == 0 and "--max-memory" in r.out and "1 GiB" in r.out
