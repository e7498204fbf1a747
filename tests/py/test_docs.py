"""The repository's documents as a stranger gets them: every relative link and
anchor in the tracked Markdown resolves, no Markdown file is over 40 KB, the
README is at most 16 KB, and nothing tracked points outside the repository
(the specification is docs/spec.md, not a file beside the clone)."""
import subprocess
import sys

import pytest

from conftest import ROOT

README_MAX_BYTES = 16 * 1024
MARKDOWN_MAX_BYTES = 40 * 1024
CHECKER = ROOT / "tools" / "check_md_links.py"


def run_checker(*args):
    return subprocess.run([sys.executable, str(CHECKER), *args], cwd=ROOT,
                          capture_output=True, text=True, timeout=60)


def test_links_and_sizes():
    r = run_checker("--max-bytes", str(MARKDOWN_MAX_BYTES))
    assert r.returncode == 0, r.stdout + r.stderr
    assert " 0 problem(s)" in r.stdout, r.stdout


def test_the_size_limit_can_fail():
    # The same checker with a limit every page exceeds must fail: the check
    # above is not vacuous.
    r = run_checker("--max-bytes", "10")
    assert r.returncode == 1, r.stdout + r.stderr


def test_readme_is_short():
    size = (ROOT / "README.md").stat().st_size
    assert size <= README_MAX_BYTES, f"README.md is {size} bytes"


@pytest.mark.parametrize("outside", ["design.md", "../shared"])
def test_nothing_points_outside(outside):
    files = subprocess.run(["git", "grep", "-l", "-F", outside], cwd=ROOT,
                           capture_output=True, text=True).stdout.split()
    files = [f for f in files if f != "tests/py/test_docs.py"]
    assert files == [], f"{outside} named in {files}"
