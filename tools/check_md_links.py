#!/usr/bin/env python3
"""Relative links and anchors in the repository's Markdown files must resolve.

    python3 tools/check_md_links.py [--allow-missing PATH ...] [--max-bytes N]

Checks every [text](target) and [text]: target in every tracked *.md file:
a relative target must exist (file or folder), and a #fragment must be the
GitHub anchor of a heading in the target file (or in the same file).
Absolute URLs are not fetched. --allow-missing names files that may be
absent (a page written on another branch); --max-bytes fails any Markdown
file larger than N bytes. Exit 1 on any broken link, 0 otherwise."""
import argparse
import os
import re
import subprocess
import sys

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
LINK = re.compile(r"(?<!\!)\[(?:[^\]\\]|\\.)*\]\(([^)\s]+)(?:\s+\"[^\"]*\")?\)")
IMAGE = re.compile(r"!\[(?:[^\]\\]|\\.)*\]\(([^)\s]+)\)")
REFDEF = re.compile(r"^\s*\[[^\]]+\]:\s*(\S+)", re.M)
FENCE = re.compile(r"^(```|~~~).*?^\1", re.M | re.S)
CODE = re.compile(r"`[^`\n]*`")


def slug(heading):
    """GitHub's anchor for a heading's text."""
    s = heading.strip().lower()
    s = re.sub(r"<[^>]+>", "", s)
    s = re.sub(r"\[([^\]]*)\]\([^)]*\)", r"\1", s)
    s = re.sub(r"[^\w\- ]", "", s)
    return s.replace(" ", "-")


def anchors(path, cache={}):
    if path not in cache:
        text = FENCE.sub("", open(path, encoding="utf-8").read())
        seen, out = {}, set()
        for m in re.finditer(r"^#{1,6}\s+(.*?)\s*#*\s*$", text, re.M):
            a = slug(m.group(1))
            n = seen.get(a, 0)
            seen[a] = n + 1
            out.add(a if n == 0 else f"{a}-{n}")
        out |= set(re.findall(r"<a\s+(?:name|id)=\"([^\"]+)\"", text))
        cache[path] = out
    return cache[path]


def md_files():
    out = subprocess.run(["git", "ls-files", "*.md"], cwd=ROOT, capture_output=True,
                         text=True, check=True).stdout.split()
    return [os.path.join(ROOT, f) for f in out if os.path.exists(os.path.join(ROOT, f))]


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--allow-missing", nargs="*", default=[])
    ap.add_argument("--max-bytes", type=int)
    a = ap.parse_args()
    allowed = {os.path.normpath(os.path.join(ROOT, p)) for p in a.allow_missing}
    bad = 0
    files = md_files()
    for f in files:
        rel = os.path.relpath(f, ROOT)
        if a.max_bytes and os.path.getsize(f) > a.max_bytes:
            print(f"{rel}: {os.path.getsize(f)} bytes, over {a.max_bytes}")
            bad += 1
        text = open(f, encoding="utf-8").read()
        body = CODE.sub("", FENCE.sub("", text))
        targets = LINK.findall(body) + IMAGE.findall(body) + REFDEF.findall(body)
        for t in targets:
            if re.match(r"^[a-z][a-z0-9+.-]*:", t, re.I):
                continue  # http:, mailto: ...
            path, _, frag = t.partition("#")
            dest = os.path.normpath(os.path.join(os.path.dirname(f), path)) if path else f
            if not os.path.exists(dest):
                if dest in allowed:
                    continue
                print(f"{rel}: {t}: no such file")
                bad += 1
                continue
            if frag and dest.endswith(".md") and frag not in anchors(dest):
                print(f"{rel}: {t}: no heading with that anchor")
                bad += 1
    print(f"{len(files)} Markdown files, {bad} problem(s)")
    return 1 if bad else 0


if __name__ == "__main__":
    sys.exit(main())
