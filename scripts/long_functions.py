#!/usr/bin/env python3
"""List, per crate of the workspace (and the binary's src/), the functions longer than N lines
(default 100), longest first, for the record (docs/architecture.md, "Modules"). A function's length
runs from its `fn` line to its closing brace. Code under `#[cfg(test)]` and `#[test]` functions are
left out unless --tests is given. Always exits 0.

Usage: scripts/long_functions.py [--lines N] [--tests] [workspace root]
"""

import argparse
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import rust_source  # noqa: E402


def functions(path, tests):
    """(name, first line, line count) of every function with a body in the file."""
    toks = rust_source.tokens(rust_source.strip(rust_source.read(path)))
    found = []
    skip_to = -1  # tokens before this index belong to a skipped test item
    depth = 0
    for i, (t, line) in enumerate(toks):
        if t == "{":
            depth += 1
        elif t == "}":
            depth -= 1
        if i < skip_to:
            continue
        if t == "#" and not tests and i + 2 < len(toks) and toks[i + 1][0] == "[":
            attr = [a for a, _ in toks[i + 2:i + 8]]
            if attr[:1] == ["test"] or (attr[:1] == ["cfg"] and "test" in attr):
                skip_to = rust_source.item_end(toks, rust_source.matching_close(toks, i + 1) + 1)
            continue
        if t == "fn" and i + 1 < len(toks) and toks[i + 1][0].isidentifier():
            end = _body_end(toks, i)
            if end is not None:
                found.append((toks[i + 1][0], line, toks[end][1] - line + 1))
    return found


def _body_end(toks, i):
    """Index of the closing brace of the body of the fn at toks[i], None for a declaration."""
    end = rust_source.item_end(toks, i)
    return end - 1 if toks[end - 1][0] == "}" else None


def main():
    here = os.path.dirname(os.path.abspath(__file__))
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--lines", type=int, default=100)
    ap.add_argument("--tests", action="store_true", help="include test code")
    ap.add_argument("root", nargs="?", default=os.path.join(here, ".."))
    args = ap.parse_args()
    root = os.path.abspath(args.root)
    for label, roots in rust_source.crates(root):
        src = os.path.dirname(roots[0])
        rows = []
        for d, _, files in os.walk(src):
            for f in sorted(files):
                if f.endswith(".rs"):
                    p = os.path.join(d, f)
                    for name, line, n in functions(p, args.tests):
                        if n > args.lines:
                            rows.append((n, os.path.relpath(p, root), line, name))
        print(f"{label}: {len(rows)} function(s) over {args.lines} lines")
        for n, p, line, name in sorted(rows, key=lambda r: (-r[0], r[1], r[2])):
            print(f"  {n:4} {p}:{line} {name}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
