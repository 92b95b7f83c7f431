#!/usr/bin/env python3
"""List, per crate of the workspace (and the binary's src/), the pairs of source files that import
each other; exit 1 when there is one (docs/architecture.md, "Modules").

An import of file B by file A is a path in A that names B's module or an item in it: `use crate::b`,
`use crate::b::Item`, `use super::Item` (the parent's file), `use crate::{b, c}`, an inline path such
as `crate::b::f()` or `super::b::f()`, or a path through a child module of A (`b::f()` in b's
parent). A module nested in a file belongs to that file, and a path to a module's item counts as
an import of the module's file, so a module and its parent are counted by file too. Not counted:
- a parent's `pub use` of its own descendants (the crate's or module's facade publishing its
  tree, not code that uses it);
- code under `#[cfg(test)]` (a test may reach anywhere).

Usage: scripts/import_cycles.py [workspace root]  (default: the directory above scripts/)
"""

import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import rust_source  # noqa: E402


class Crate:
    def __init__(self, label):
        self.label = label
        self.modules = {}  # module path (tuple) -> file
        self.uses = []  # (file, module path, segments, line, is_pub)

    def children(self, path):
        return {p[-1] for p in self.modules if len(p) == len(path) + 1 and p[:-1] == path}


def module_dir(file, path_in_file):
    """Directory where `mod x;` declared in `file` (inside its inline modules `path_in_file`) lives."""
    d, base = os.path.dirname(file), os.path.basename(file)
    if base not in ("lib.rs", "main.rs", "mod.rs"):
        d = os.path.join(d, base[:-3])
    return os.path.join(d, *path_in_file)


def is_test_cfg(attr):
    return len(attr) > 2 and attr[0] == "cfg" and "test" in attr


def parse_use_tree(toks, i, prefix, out):
    """Parse one use tree at toks[i]; append full segment lists to out; return the next index."""
    segs = list(prefix)
    while i < len(toks):
        t = toks[i][0]
        if t == "{":
            i += 1
            while toks[i][0] != "}":
                i = parse_use_tree(toks, i, segs, out)
                if toks[i][0] == ",":
                    i += 1
            return i + 1
        if t == "*":
            out.append(segs + ["*"])
            return i + 1
        if t == "::":
            i += 1
            continue
        if t == "self" and segs and toks[i - 1][0] != "::":
            out.append(segs)  # `use a::{self, ...}`
            return i + 1
        if t.isidentifier() or t == "$":
            segs.append("crate" if t == "$" else t)
            i += 2 if t == "$" else 1
            if i < len(toks) and toks[i][0] == "as":
                i += 2
            if i < len(toks) and toks[i][0] != "::":
                out.append(segs)
                return i
            continue
        return i
    return i


def parse_file(crate, file, path, pending):
    text = rust_source.strip(rust_source.read(file))
    toks = rust_source.tokens(text)
    stack = []  # (module path, depth at which its block closes)
    inline = []  # inline module names within this file
    depth = 0
    i = 0
    while i < len(toks):
        t, line = toks[i]
        cur = path + tuple(inline)
        if t == "#" and i + 1 < len(toks) and toks[i + 1][0] in "[!":
            j = i + 1 if toks[i + 1][0] == "[" else i + 2
            close = rust_source.matching_close(toks, j)
            attr = [a for a, _ in toks[j + 1:close]]
            if toks[i + 1][0] == "[" and is_test_cfg(attr):
                # Skip further attributes, then the item.
                k = close + 1
                while k + 1 < len(toks) and toks[k][0] == "#" and toks[k + 1][0] == "[":
                    k = rust_source.matching_close(toks, k + 1) + 1
                i = rust_source.item_end(toks, k)
                continue
            i = close + 1
            continue
        if t == "{":
            depth += 1
        elif t == "}":
            depth -= 1
            if stack and stack[-1][1] == depth:
                stack.pop()
                inline.pop()
        elif t == "mod" and i + 2 < len(toks) and toks[i + 1][0].isidentifier():
            name, nxt = toks[i + 1][0], toks[i + 2][0]
            if nxt == ";":
                d = module_dir(file, inline)
                for cand in (os.path.join(d, name + ".rs"), os.path.join(d, name, "mod.rs")):
                    if os.path.isfile(cand):
                        crate.modules[cur + (name,)] = cand
                        pending.append((cand, cur + (name,)))
                        break
                i += 3
                continue
            if nxt == "{":
                crate.modules[cur + (name,)] = file
                stack.append((cur + (name,), depth))
                inline.append(name)
                depth += 1
                i += 3
                continue
        elif t == "use" and (i == 0 or toks[i - 1][0] != "::"):
            back = [a for a, _ in toks[max(0, i - 5):i]]
            is_pub = "pub" in back[-1:] or (back[-1:] == [")"] and "pub" in back)
            paths = []
            j = parse_use_tree(toks, i + 1, [], paths)
            for p in paths:
                crate.uses.append((file, cur, p, line, is_pub))
            i = j
            continue
        elif (t in ("crate", "super", "self") or t.isidentifier()) and i + 1 < len(toks) \
                and toks[i + 1][0] == "::" and (i == 0 or toks[i - 1][0] not in ("::", ".")):
            segs, j = [t], i + 1
            while j + 1 < len(toks) and toks[j][0] == "::" and toks[j + 1][0].isidentifier():
                segs.append(toks[j + 1][0])
                j += 2
            crate.uses.append((file, cur, segs, line, False))
            i = j
            continue
        i += 1


def resolve(crate, cur, segs):
    """The module path a use path reaches (None: another crate, a primitive or a local item)."""
    if not segs:
        return None
    k = 0
    if segs[0] == "crate":
        base, k = (), 1
    elif segs[0] in ("super", "self"):
        base = cur
        while k < len(segs) and segs[k] in ("super", "self"):
            base = base[:-1] if segs[k] == "super" else base
            k += 1
    elif segs[0] in crate.children(cur):
        base = cur
    else:
        return None
    while k < len(segs) and segs[k] in crate.children(base):
        base = base + (segs[k],)
        k += 1
    return base


def analyse(label, roots):
    crate = Crate(label)
    for root in roots:
        crate.modules[()] = root
        pending = [(root, ())]
        while pending:
            file, path = pending.pop()
            parse_file(crate, file, path, pending)
    edges = {}
    for file, cur, segs, line, is_pub in crate.uses:
        target = resolve(crate, cur, segs)
        if target is None:
            continue
        dst = crate.modules.get(target)
        if dst is None or dst == file:
            continue
        if is_pub and target[: len(cur)] == cur:
            continue  # a facade's re-export of its own descendant
        edges.setdefault((file, dst), (line, "::".join(segs)))
    pairs = []
    for (a, b), (line, what) in sorted(edges.items()):
        if a < b and (b, a) in edges:
            pairs.append((a, b, line, what, *edges[(b, a)]))
    return pairs


def main():
    here = os.path.dirname(os.path.abspath(__file__))
    root = os.path.abspath(sys.argv[1] if len(sys.argv) > 1 else os.path.join(here, ".."))
    total = 0
    for label, roots in rust_source.crates(root):
        # The lib and the binary's main.rs are separate crates: analyse each root on its own.
        for r in roots:
            pairs = analyse(label, [r])
            for a, b, la, wa, lb, wb in pairs:
                ra, rb = os.path.relpath(a, root), os.path.relpath(b, root)
                print(f"{label}: {ra} <-> {rb}  ({ra}:{la} {wa}; {rb}:{lb} {wb})")
            total += len(pairs)
    if total:
        print(f"{total} pair(s) of files import each other")
        return 1
    print("no two files of one crate import each other")
    return 0


if __name__ == "__main__":
    sys.exit(main())
