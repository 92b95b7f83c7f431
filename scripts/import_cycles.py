#!/usr/bin/env python3
"""List, per crate of the workspace (and the binary's src/), the import cycles of any length among
its source files; exit 1 when there is one (docs/architecture.md, "Modules").

The files of a crate form a graph: an edge from file A to file B when A depends on B. Every
strongly connected component of more than one file is a cycle; each is printed with one shortest
cycle through it (every step with the line and path that makes it), and the last line counts them
("N intra-crate cycles"; `--count` prints only that line and the per-crate counts).

A depends on B when
- A imports B: a path in A that names B's module or an item in it: `use crate::b`,
  `use crate::b::Item`, `use super::Item` (the parent's file), `use crate::{b, c}`, an inline path
  such as `crate::b::f()` or `super::b::f()`, or a path through a child module of A (`b::f()` in
  b's parent). A module nested in a file belongs to that file, and a path to a module's item counts
  as an import of the module's file, so a module and its parent are counted by file too; an item
  a facade re-exports (`crate::X` with `pub use b::X` in lib.rs) counts as an import of the file
  that defines it (b), not of the facade's;
- A calls a method defined in B: `x.foo()` (or `x.foo::<T>()`) in A where `fn foo` is defined in
  an `impl` or `trait` block of B and of no other file of the crate. A method name defined in
  several files, or also by another crate of the workspace (`x.decimation()` may be noise's
  `OutputFilter::decimation` in diagnose), is ambiguous (which one a call reaches needs types)
  and is ignored, as are the names of std's common methods and traits (`new`, `len`, `iter`,
  `clone`, `fmt`, `from`, `into`, `default`, ...: COMMON below), which a call far more often
  means than the crate's own. Calls are matched by name only: a crate's method that shares its
  name with a method of a non-workspace dependency not in COMMON is taken as the crate's.
Not counted:
- a parent's `pub use` of its own descendants (the crate's or module's facade publishing its
  tree, not code that uses it);
- code under `#[cfg(test)]` (a test may reach anywhere).

Usage: scripts/import_cycles.py [--count] [workspace root]  (default: the directory above scripts/)
"""

import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import rust_source  # noqa: E402

# Method names of std's types and traits (and of the common derives and operators): a call of one
# of these is not taken as a call of the crate's method of that name.
COMMON = set("""
    new default clone clone_from fmt from into try_from try_into from_str to_string to_owned
    as_ref as_mut borrow borrow_mut deref deref_mut drop eq ne cmp partial_cmp lt le gt ge hash
    add sub mul div rem neg not index index_mut add_assign sub_assign mul_assign div_assign
    len is_empty iter iter_mut into_iter next next_back size_hint get get_mut insert remove push
    pop clear contains extend append truncate resize reserve with_capacity capacity first last
    split_at chunks windows sort sort_by sort_unstable sort_by_key dedup retain swap reverse
    map filter filter_map fold sum product count min max min_by max_by min_by_key max_by_key zip
    chain rev enumerate skip take step_by collect any all find position flat_map flatten copied
    cloned for_each take_while skip_while last nth peekable cycle partition unzip scan
    unwrap unwrap_or unwrap_or_else unwrap_or_default expect ok err ok_or ok_or_else is_some
    is_none is_ok is_err and_then or_else map_err map_or map_or_else as_deref
    abs sqrt powi powf exp ln log10 log2 sin cos tan atan2 floor ceil round trunc signum
    is_finite is_nan hypot mul_add clamp to_bits from_bits
    as_str as_slice as_bytes to_vec join split trim lines chars bytes parse starts_with ends_with
    write write_str write_all write_fmt read read_to_string flush display source description
    serialize deserialize call set run apply name value kind key keys values entry with
    sin_cos recip exp_m1 ln_1p cbrt asin acos atan sinh cosh tanh to_degrees to_radians
    next_u32 next_u64 fill_bytes fill load store finish lock spawn send recv elapsed
    copy_from_slice clone_from_slice drain or_insert or_insert_with or_default norm dot cross
    transpose
""".split())


class Crate:
    def __init__(self, label):
        self.label = label
        self.modules = {}  # module path (tuple) -> file
        self.uses = []  # (file, module path, segments, line, is_pub)
        self.methods = {}  # method name -> files whose impl / trait blocks define it
        self.calls = []  # (file, method name, line)

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


def is_item_start(toks, i):
    """Does the keyword at toks[i] (`impl`, `trait`) begin an item, not a type (`-> impl Fn`)?"""
    if toks[i][0] == "trait":
        return i + 1 < len(toks) and toks[i + 1][0].isidentifier()
    k = i - 1
    if k >= 0 and toks[k][0] == "unsafe":
        k -= 1
    return k < 0 or toks[k][0] in (";", "{", "}", "]")


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
    blocks = []  # depths inside the impl / trait blocks open at this point
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
        if t in ("impl", "trait") and is_item_start(toks, i):
            j = i + 1
            while j < len(toks) and toks[j][0] not in ("{", ";"):
                j = rust_source.matching_close(toks, j) if toks[j][0] in "([" else j
                j += 1
            if j < len(toks) and toks[j][0] == "{":
                blocks.append(depth + 1)
                depth += 1
                i = j + 1
                continue
        if t == "fn" and blocks and blocks[-1] == depth and i + 1 < len(toks) \
                and toks[i + 1][0].isidentifier():
            crate.methods.setdefault(toks[i + 1][0], set()).add(file)
        if t == "." and i + 2 < len(toks) and toks[i + 1][0].isidentifier() \
                and toks[i + 2][0] in ("(", "::") and (i == 0 or toks[i - 1][0] != "."):
            crate.calls.append((file, toks[i + 1][0], toks[i + 1][1]))
        if t == "{":
            depth += 1
        elif t == "}":
            depth -= 1
            if blocks and blocks[-1] == depth + 1:
                blocks.pop()
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


def resolve(crate, cur, segs, facade=None):
    """The module path a use path reaches (None: another crate, a primitive or a local item).
    With `facade` ({(module path, name): module path}), an item a module re-exports from its
    descendants is followed to the module that defines it."""
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
    while k < len(segs):
        if segs[k] in crate.children(base):
            base = base + (segs[k],)
        elif facade and (base, segs[k]) in facade:
            base = facade[(base, segs[k])]
        else:
            break
        k += 1
    return base


def parse_crate(label, root):
    crate = Crate(label)
    crate.modules[()] = root
    pending = [(root, ())]
    while pending:
        file, path = pending.pop()
        parse_file(crate, file, path, pending)
    return crate


def analyse(crate, foreign=frozenset()):
    """The crate's dependency edges between files: {(a, b): (line in a, what)}. `foreign`: the
    method names the workspace's other crates define (a call of one is ambiguous)."""
    facade = {}  # (module, name it re-exports from a descendant) -> the module defining it
    for file, cur, segs, line, is_pub in crate.uses:
        target = resolve(crate, cur, segs)
        if is_pub and target is not None and target[: len(cur)] == cur and segs[-1] != "*":
            facade.setdefault((cur, segs[-1]), target)
    edges = {}
    for file, cur, segs, line, is_pub in crate.uses:
        target = resolve(crate, cur, segs)
        if target is None:
            continue
        if is_pub and target[: len(cur)] == cur:
            continue  # a facade's re-export of its own descendant
        target = resolve(crate, cur, segs, facade)
        dst = crate.modules.get(target)
        if dst is None or dst == file:
            continue
        edges.setdefault((file, dst), (line, "::".join(segs)))
    for file, name, line in crate.calls:
        defined = crate.methods.get(name, ())
        if name in COMMON or name in foreign or len(defined) != 1:
            continue
        (dst,) = defined
        if dst != file:
            edges.setdefault((file, dst), (line, "." + name + "()"))
    return edges


def components(nodes, succ):
    """The strongly connected components of more than one node (Tarjan), each sorted."""
    index, low, on, stack, found = {}, {}, set(), [], []
    for start in nodes:
        if start in index:
            continue
        work = [(start, iter(succ.get(start, ())))]
        index[start] = low[start] = len(index)
        stack.append(start)
        on.add(start)
        while work:
            v, it = work[-1]
            w = next(it, None)
            if w is not None:
                if w not in index:
                    index[w] = low[w] = len(index)
                    stack.append(w)
                    on.add(w)
                    work.append((w, iter(succ.get(w, ()))))
                elif w in on:
                    low[v] = min(low[v], index[w])
                continue
            work.pop()
            if work:
                low[work[-1][0]] = min(low[work[-1][0]], low[v])
            if low[v] == index[v]:
                comp = []
                while True:
                    w = stack.pop()
                    on.discard(w)
                    comp.append(w)
                    if w == v:
                        break
                if len(comp) > 1:
                    found.append(sorted(comp))
    return sorted(found)


def shortest_cycle(comp, succ):
    """One shortest cycle through the component: its files in order, the first not repeated."""
    inside = set(comp)
    best = None
    for start in comp:
        prev, frontier, done = {start: None}, [start], None
        while frontier and done is None:
            nxt = []
            for v in frontier:
                for w in sorted(succ.get(v, ())):
                    if w not in inside:
                        continue
                    if w == start:
                        done = v
                        break
                    if w not in prev:
                        prev[w] = v
                        nxt.append(w)
                if done is not None:
                    break
            frontier = nxt
        if done is None:
            continue
        path = [done]
        while prev[path[-1]] is not None:
            path.append(prev[path[-1]])
        path.reverse()
        if best is None or len(path) < len(best):
            best = path
    return best


def main():
    args = sys.argv[1:]
    count_only = "--count" in args
    args = [a for a in args if a != "--count"]
    here = os.path.dirname(os.path.abspath(__file__))
    root = os.path.abspath(args[0] if args else os.path.join(here, ".."))
    total = 0
    # The lib and the binary's main.rs are separate crates: each root is analysed on its own.
    parsed = [(label, [parse_crate(label, r) for r in roots])
              for label, roots in rust_source.crates(root)]
    for label, crates in parsed:
        found = files = 0
        for crate in crates:
            foreign = {name for _, others in parsed for c in others if c is not crate
                       for name in c.methods}
            edges = analyse(crate, foreign)
            succ = {}
            for a, b in edges:
                succ.setdefault(a, set()).add(b)
            comps = components(sorted(succ), succ)
            found += len(comps)
            files += sum(len(c) for c in comps)
            for comp in [] if count_only else comps:
                cycle = shortest_cycle(comp, succ)
                rel = [os.path.relpath(f, root) for f in cycle]
                print(f"{label}: {len(comp)} files in a cycle; shortest: "
                      + " -> ".join(rel + rel[:1]))
                for a, b in zip(cycle, cycle[1:] + cycle[:1]):
                    line, what = edges[(a, b)]
                    print(f"    {os.path.relpath(a, root)}:{line} {what}")
                others = sorted(set(comp) - set(cycle))
                if others:
                    print("    also in it: " + ", ".join(os.path.relpath(f, root) for f in others))
        if count_only:
            print(f"{label}: {found} cycle(s), {files} file(s) in them")
        total += found
    print(f"{total} intra-crate cycles")
    return 1 if total else 0


if __name__ == "__main__":
    sys.exit(main())
