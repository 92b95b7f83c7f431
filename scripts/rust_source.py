"""Shared reading of the workspace's Rust sources for scripts/import_cycles.py and
scripts/long_functions.py (python3, standard library only).

`strip(text)` blanks comments, string and character literals (keeping line breaks and lengths, so
positions and line numbers stay valid); `tokens(text)` splits stripped text into identifiers and
punctuation with their line numbers; `crates(root)` lists the workspace's crates with their
source roots (crates/*/src/lib.rs, and the binary package's src/lib.rs and src/main.rs).
"""

import bisect
import os
import re

TOKEN = re.compile(r"[A-Za-z_][A-Za-z0-9_]*|::|[{}()\[\];,*#!<>=&]|\S")


def strip(text):
    """Comments, strings and char literals replaced by spaces; newlines kept."""
    out = list(text)
    i, n = 0, len(text)

    def blank(a, b):
        for k in range(a, b):
            if out[k] != "\n":
                out[k] = " "

    while i < n:
        c = text[i]
        if text.startswith("//", i):
            j = text.find("\n", i)
            j = n if j < 0 else j
            blank(i, j)
            i = j
        elif text.startswith("/*", i):
            depth, j = 1, i + 2
            while j < n and depth:
                if text.startswith("/*", j):
                    depth, j = depth + 1, j + 2
                elif text.startswith("*/", j):
                    depth, j = depth - 1, j + 2
                else:
                    j += 1
            blank(i, j)
            i = j
        elif c == "r" and re.match(r'r#*"', text[i:i + 260]) and not _ident_char(text, i - 1):
            hashes = re.match(r'r(#*)"', text[i:]).group(1)
            end = text.find('"' + hashes, i + 2 + len(hashes))
            j = n if end < 0 else end + 1 + len(hashes)
            blank(i, j)
            i = j
        elif c == '"':
            j = i + 1
            while j < n and text[j] != '"':
                j += 2 if text[j] == "\\" else 1
            blank(i, j + 1)
            i = j + 1
        elif c == "'":
            # A char literal ('a', '\n', '\u{..}'), else a lifetime or label ('a).
            m = re.match(r"'(\\u\{[0-9a-fA-F]+\}|\\.|[^\\'])'", text[i:i + 12])
            if m:
                blank(i, i + m.end())
                i += m.end()
            else:
                i += 1
        else:
            i += 1
    return "".join(out)


def _ident_char(text, k):
    return k >= 0 and (text[k].isalnum() or text[k] == "_")


def tokens(stripped):
    """(token, line) pairs."""
    line_starts = [0]
    for m in re.finditer("\n", stripped):
        line_starts.append(m.end())
    out = []
    for m in TOKEN.finditer(stripped):
        out.append((m.group(0), bisect.bisect_right(line_starts, m.start())))
    return out


def matching_close(toks, i):
    """Index of the bracket that closes the one at toks[i] (`(`, `[` or `{`)."""
    depth, j = 0, i
    while j < len(toks):
        t = toks[j][0]
        if t in "([{":
            depth += 1
        elif t in ")]}":
            depth -= 1
            if depth == 0:
                return j
        j += 1
    return j


def item_end(toks, i):
    """Index just past the item starting at toks[i]: after its `;`, or after the closing `}` of
    its first block at bracket depth 0."""
    j = i
    while j < len(toks):
        t = toks[j][0]
        if t in "([{":
            close = matching_close(toks, j)
            if t == "{":
                return close + 1
            j = close + 1
        elif t == ";":
            return j + 1
        else:
            j += 1
    return j


def crates(root):
    """(crate label, [source root files]) for every crate of the workspace, in name order."""
    found = []
    crates_dir = os.path.join(root, "crates")
    for name in sorted(os.listdir(crates_dir)) if os.path.isdir(crates_dir) else []:
        lib = os.path.join(crates_dir, name, "src", "lib.rs")
        if os.path.isfile(lib):
            found.append(("crates/" + name, [lib]))
    roots = [os.path.join(root, "src", f) for f in ("lib.rs", "main.rs")]
    roots = [r for r in roots if os.path.isfile(r)]
    if roots:
        found.append(("src (binary)", roots))
    return found


def read(path):
    with open(path, encoding="utf-8") as f:
        return f.read()
