"""Shared fixtures: the qrtplan binary and a helper that plans a scene."""
import json
import os
import re
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT / "tools"))

BIN = Path(os.environ.get("QRTPLAN_BIN", ROOT / "build" / "bin" / "qrtplan"))


@pytest.fixture(scope="session")
def qrtplan():
    if not BIN.is_file():
        pytest.fail(f"qrtplan binary not found at {BIN}: run `make` first "
                    "(or set QRTPLAN_BIN)")
    return BIN


def run_cli(args, timeout=120):
    return subprocess.run([str(BIN), *map(str, args)], capture_output=True,
                          text=True, timeout=timeout)


def max_points():
    """QRT_MAX_POINTS of this build (the exact table's size), as `qrtplan
    --version` prints it."""
    r = run_cli(["--version"])
    m = re.search(r"(\d+) points exact", r.stdout)
    assert r.returncode == 0 and m, r.stdout
    return int(m.group(1))


def plan_scene(scene, directory, *flags, name="scene"):
    """Write scene, plan it; returns (returncode, plan dict or None, stderr)."""
    path = Path(directory) / f"{name}.json"
    path.write_text(json.dumps(scene))
    r = run_cli(["plan", path, *flags])
    plan = json.loads(r.stdout) if r.returncode == 0 else None
    return r.returncode, plan, r.stderr
