#!/usr/bin/env python3
"""Structure checks of the workspace (run by .ci/run):

1. No import circle between modules. For every module, the graph of its child
   modules must be acyclic: a reference from module A to an item of module B (a
   `use` or an inline `crate::`/`super::` path), where neither is an ancestor of the
   other, is an edge between the two children of their lowest common ancestor that
   contain A and B. (A parent using its children, or a child its parent, is layering,
   not a circle.)
2. No hand-written file over 800 lines (generated tables, data and figures aside).

`--report` prints the findings and exits 0; without it, findings exit 1.
"""

import os
import re
import subprocess
import sys

LIMIT = 800
# generated or data files: (path prefix or suffix) -> why
GENERATED = (
    "Cargo.lock",
    "include/coagula.h",  # cbindgen
    "_table.rs",  # generated constant tables (qmc, ziggurat)
    ".svg",
    ".png",
    ".txt",
    ".csv",
    ".proptest-regressions",
    "fuzz/corpus/",
    "core/tests/data/",
)

CRATES = {"core": "core/src/lib.rs", "ffi": "ffi/src/lib.rs", "cli": "cli/src/main.rs",
          "fuzz": "fuzz/src/lib.rs", "python": "python/src/lib.rs"}

MOD_DECL = re.compile(r"^\s*(?:pub(?:\([^)]*\))?\s+)?mod\s+([a-z_0-9]+)\s*;", re.M)
PATH_RE = re.compile(r"\b(crate|super|self)((?:::[A-Za-z_][A-Za-z_0-9]*)+)")
USE_RE = re.compile(r"\buse\s+([^;]+);", re.S)


def strip_comments(text):
    text = re.sub(r"/\*.*?\*/", "", text, flags=re.S)
    return re.sub(r"//[^\n]*", "", text)


def load_crate(root_file):
    """Maps module path (tuple) -> file, following `mod x;` declarations."""
    mods = {}

    def walk(path, file, is_dir_owner):
        mods[path] = file
        text = strip_comments(open(file, encoding="utf-8").read())
        base = os.path.dirname(file)
        if not is_dir_owner:
            base = os.path.join(base, os.path.splitext(os.path.basename(file))[0])
        for name in MOD_DECL.findall(text):
            cands = [os.path.join(base, name + ".rs"), os.path.join(base, name, "mod.rs")]
            for c in cands:
                if os.path.exists(c):
                    walk(path + (name,), c, c.endswith("mod.rs"))
                    break

    walk((), root_file, True)
    return mods


def expand_use(tree):
    """`a::{b, c::{d}}` -> ['a::b', 'a::c::d'] (strings without `as` renames)."""
    tree = re.sub(r"\s+", "", tree)
    out = []

    def rec(prefix, s):
        # split top-level commas
        depth, start, parts = 0, 0, []
        for i, ch in enumerate(s):
            if ch == "{":
                depth += 1
            elif ch == "}":
                depth -= 1
            elif ch == "," and depth == 0:
                parts.append(s[start:i])
                start = i + 1
        parts.append(s[start:])
        for p in parts:
            if not p:
                continue
            m = re.match(r"^(.*?)::\{(.*)\}$", p)
            if m:
                rec(prefix + m.group(1) + "::", m.group(2))
            elif p.startswith("{") and p.endswith("}"):
                rec(prefix, p[1:-1])
            else:
                out.append(prefix + p.split("as")[0] if "::" in p and p.endswith(")") else prefix + re.sub(r"as[A-Za-z_0-9]+$", "", p))

    rec("", tree)
    return out


def resolve(mods, here, path):
    """The module a path (`crate::a::b::Item`, `super::x`) falls in."""
    segs = path.split("::")
    if segs[0] == "crate":
        cur, rest = (), segs[1:]
    elif segs[0] in ("super", "self"):
        cur = here
        while segs and segs[0] in ("super", "self"):
            if segs[0] == "super":
                cur = cur[:-1]
            segs = segs[1:]
        rest = segs
    else:
        return None
    for s in rest:
        if cur + (s,) in mods:
            cur = cur + (s,)
        else:
            break
    return cur


def module_of_line(mods_by_file, file):
    return mods_by_file[file]


def crate_edges(mods):
    """Edges (a, b) between module paths from references in each module's file."""
    edges = {}
    for here, file in mods.items():
        text = strip_comments(open(file, encoding="utf-8").read())
        refs = []
        for u in USE_RE.findall(text):
            for p in expand_use(u):
                if p.startswith(("crate::", "super::", "self::")) or p in ("super", "self"):
                    refs.append(p)
        refs += [m.group(1) + m.group(2) for m in PATH_RE.finditer(text)]
        for p in refs:
            there = resolve(mods, here, p)
            if there is None or there == here:
                continue
            n = min(len(here), len(there))
            if here[:n] == there[:n]:
                continue  # ancestor or descendant
            k = 0
            while here[k] == there[k]:
                k += 1
            a, b = here[: k + 1], there[: k + 1]
            edges.setdefault((a, b), set()).add((here, there))
    return edges


def cycles(edges):
    """Strongly connected components of size > 1 per parent module."""
    graph = {}
    for a, b in edges:
        graph.setdefault(a, set()).add(b)
        graph.setdefault(b, set())
    index, low, stack, on, out = {}, {}, [], set(), []
    counter = [0]

    def strong(v):
        index[v] = low[v] = counter[0]
        counter[0] += 1
        stack.append(v)
        on.add(v)
        for w in graph[v]:
            if w not in index:
                strong(w)
                low[v] = min(low[v], low[w])
            elif w in on:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            comp = []
            while True:
                w = stack.pop()
                on.discard(w)
                comp.append(w)
                if w == v:
                    break
            if len(comp) > 1:
                out.append(sorted(comp))

    sys.setrecursionlimit(10000)
    for v in sorted(graph):
        if v not in index:
            strong(v)
    return out


def long_files():
    files = subprocess.run(["git", "ls-files", "-co", "--exclude-standard"],
                           capture_output=True, text=True, check=True).stdout.split()
    found = []
    for f in files:
        if any(f.startswith(g) or f.endswith(g) for g in GENERATED) or not os.path.isfile(f):
            continue
        try:
            n = sum(1 for _ in open(f, encoding="utf-8"))
        except UnicodeDecodeError:
            continue
        if n > LIMIT:
            found.append((n, f))
    return sorted(found, reverse=True)


def main():
    report = "--report" in sys.argv
    os.chdir(os.path.join(os.path.dirname(os.path.abspath(__file__)), ".."))
    bad = 0
    for crate, root in CRATES.items():
        if not os.path.exists(root):
            continue
        mods = load_crate(root)
        edges = crate_edges(mods)
        for comp in cycles(edges):
            bad += 1
            names = ["::".join(c) or "crate" for c in comp]
            print(f"import circle in {crate}: {' <-> '.join(names)}")
            for (a, b), why in sorted(edges.items()):
                if a in comp and b in comp:
                    for here, there in sorted(why)[:3]:
                        print(f"    {'::'.join(here)} uses {'::'.join(there) or 'crate'}")
    for n, f in long_files():
        bad += 1
        print(f"{f}: {n} lines (over {LIMIT})")
    if bad and not report:
        sys.exit(1)
    if not bad:
        print("structure: no import circle, no hand-written file over", LIMIT, "lines")


if __name__ == "__main__":
    main()
