"""servo_sim's command line: values that would wrap a 32-bit CiA 402 object
or name a drive that is not simulated are refused before the bus is opened
(so these run on a machine without SocketCAN)."""
import subprocess

import pytest

from conftest import BIN

SIM = BIN.parent / "servo_sim"  # built beside qrtplan


def run_sim(args):
    if not SIM.is_file():
        pytest.fail(f"{SIM} not found: run `make` first")
    return subprocess.run([str(SIM), *args, "--iface", "qrt_no_such_bus",
                           "--duration", "0.1"],
                          capture_output=True, text=True, timeout=30)


@pytest.mark.parametrize("args,words", [
    (["--limit", "2:1:5junk"], "bad value for --limit"),
    (["--limit", "200:1:5"], "bad value for --limit"),
    (["--limit", "2:-99999999999:5"], "bad value for --limit"),
    (["--limit", "2:1:2147483648"], "bad value for --limit"),
    (["--limit", "2:5:1"], "bad value for --limit"),
    (["--limit", "5:1:2"], "--limit for node 5, not in --nodes"),
    (["--start-deg", "100000,0,0", "--counts-per-deg", "100000"],
     "beyond a 32-bit position"),
    (["--start-deg", "nan,0,0"], "bad value for --start-deg"),
    (["--counts-per-deg", "inf"], "bad value for --counts-per-deg"),
])
def test_refused_before_the_bus_opens(args, words):
    r = run_sim(args)
    assert r.returncode == 2, r.stderr
    assert words in r.stderr
    assert "socket" not in r.stderr


def test_accepted_values_reach_the_bus():
    """The same options within range get past the checks: the run then fails
    only on the bus that does not exist (exit 1, a socket error)."""
    r = run_sim(["--nodes", "4,5,6", "--limit", "5:-2147483648:2147483647",
                 "--start-deg", "10,20,30", "--counts-per-deg", "1000"])
    assert r.returncode == 1, r.stderr
    assert "qrt_no_such_bus" in r.stderr or "socket" in r.stderr
