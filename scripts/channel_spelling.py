#!/usr/bin/env python3
"""Count the places outside crates/noise/src/channel.rs that spell an IMU channel by its name or
work it out from an index: the string literals "gx" .. "az" (and the temperature's "temp" where it
picks a log series), a list of the names (`CHANNEL_NAMES`, `CHANNELS`), and index arithmetic on
channels (`first + a`, `3 + a`, `channel < 3`). Comments, docstrings and tests are not counted
(a test may spell what it checks). Prints each place and the total; exit 0 always (a record).

Usage: scripts/channel_spelling.py [root]   (default: the directory above scripts/)
"""

import os
import re
import sys

ROOT = sys.argv[1] if len(sys.argv) > 1 else os.path.join(os.path.dirname(os.path.abspath(__file__)), "..")
SKIP_DIRS = {"target", "tests", "fuzz", ".git", "benches", "examples"}
OWNER = os.path.join("crates", "noise", "src", "channel.rs")
PATTERNS = [
    re.compile(r'"(gx|gy|gz|ax|ay|az)"'),
    re.compile(r"\b(CHANNEL_NAMES|_CHANNELS|CHANNELS)\b\s*(=|\[|\.|:)"),
    re.compile(r"\bfirst \+ a\b|\b3 \+ a\b|\bchannel < 3\b|\bc < 3\b"),
]


def code_lines(path):
    """(number, line) of code: Rust `//` comments and `#[cfg(test)]` modules and Python comments
    and docstrings left out."""
    out, in_test, depth, in_doc = [], False, 0, False
    with open(path, encoding="utf-8") as f:
        lines = f.readlines()
    for i, line in enumerate(lines, 1):
        s = line.strip()
        if path.endswith(".rs"):
            if s.startswith("#[cfg(test)]"):
                in_test, depth = True, 0
                continue
            if in_test:
                depth += line.count("{") - line.count("}")
                if depth <= 0 and "}" in line:
                    in_test = False
                continue
            if s.startswith("//"):
                continue
            line = line.split("//")[0]
        else:
            if s.startswith('"""') or s.endswith('"""'):
                if not (s.startswith('"""') and s.endswith('"""') and len(s) > 5):
                    in_doc = not in_doc
                continue
            if in_doc or s.startswith("#"):
                continue
        out.append((i, line))
    return out


def main():
    total = 0
    for d, dirs, files in os.walk(ROOT):
        dirs[:] = sorted(x for x in dirs if x not in SKIP_DIRS)
        for name in sorted(files):
            if not (name.endswith(".rs") or name.endswith(".py")) or name == "tests.rs":
                continue
            path = os.path.join(d, name)
            rel = os.path.relpath(path, ROOT)
            if rel == OWNER or rel.startswith("scripts") or "/tests/" in rel or "testutil" in rel:
                continue
            for i, line in code_lines(path):
                if any(p.search(line) for p in PATTERNS):
                    total += 1
                    print(f"{rel}:{i}: {line.strip()}")
    print(f"{total} places spell a channel by name or index outside {OWNER}")


if __name__ == "__main__":
    main()
