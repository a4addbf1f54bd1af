#!/usr/bin/env python3
"""Finds files of a crate that import each other (directly or in a longer circle).

    python3 tools/module_cycles.py [crates/model crates/import ... src]

Issue 14's rule: no module of a crate imports a module that imports it back. A file A
depends on file B when A's non-test code names an item *defined* in B through a `use`
statement or an inline `crate::`/`super::`/`self::` path; re-exports (`pub use`, the facade
of a `mod.rs` or `lib.rs`) are followed to the file that defines the item and are not
dependencies themselves. `mod x;` declarations are not dependencies. Test code (files named
`tests.rs` or under `tests/`, and everything after `#[cfg(test)]` in a file) is ignored.

Prints every circle (as a list of files) and exits 1 when there is one; prints the number
of files and edges otherwise. It reads Rust with regular expressions: enough for this
codebase's style (one item per `pub fn`/`struct`/... line, `use` trees with braces).
"""

import os
import re
import sys

ITEM = re.compile(
    r"^\s*(?:pub(?:\([^)]*\))?\s+)?(?:unsafe\s+|const\s+|async\s+|extern\s+\"C\"\s+)*"
    r"(fn|struct|enum|trait|type|const|static|union|macro_rules!)\s+([A-Za-z_][A-Za-z0-9_]*)",
    re.M,
)
MOD_DECL = re.compile(r"^\s*(?:pub(?:\([^)]*\))?\s+)?mod\s+([A-Za-z_][A-Za-z0-9_]*)\s*;", re.M)
INLINE_MOD = re.compile(r"^\s*(?:pub(?:\([^)]*\))?\s+)?mod\s+([A-Za-z_][A-Za-z0-9_]*)\s*\{", re.M)
USE = re.compile(r"^\s*(pub(?:\([^)]*\))?\s+)?use\s+([^;]+);", re.M)
INLINE_PATH = re.compile(r"(?<![A-Za-z0-9_:])((?:crate|super|self)(?:::[A-Za-z_][A-Za-z0-9_]*)+)")


def strip(text):
    """Non-test code without comments and string literals."""
    cut = text.find("#[cfg(test)]")
    if cut >= 0:
        text = text[:cut]
    text = re.sub(r"//[^\n]*", "", text)
    text = re.sub(r"/\*.*?\*/", "", text, flags=re.S)
    text = re.sub(r'r#*"(?:.|\n)*?"#*', '""', text)
    text = re.sub(r'"(?:\\.|[^"\\])*"', '""', text)
    return text


def expand(tree):
    """`a::{b, c::{d, e}}` -> [[a,b],[a,c,d],[a,c,e]] (aliases and globs kept as names)."""
    tree = re.sub(r"\s+", "", tree)
    out = []

    def walk(prefix, s):
        # split s at top-level commas
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
            if "{" in p:
                head, rest = p.split("{", 1)
                rest = rest[: rest.rfind("}")]
                head = [x for x in head.split("::") if x]
                walk(prefix + head, rest)
            else:
                name = p.split("as")[0] if re.search(r"[A-Za-z0-9_]as[A-Za-z_]", p) is None else re.split(r"(?<=[A-Za-z0-9_])as(?=[A-Za-z_])", p)[0]
                out.append(prefix + [x for x in name.split("::") if x])

    walk([], tree)
    return out


class Crate:
    def __init__(self, src):
        self.src = src
        self.files = {}  # module path tuple -> file
        self.text = {}
        root = "lib.rs" if os.path.exists(os.path.join(src, "lib.rs")) else "main.rs"
        self.load((), os.path.join(src, root))

    def load(self, modpath, path):
        text = strip(open(path, encoding="utf-8").read())
        self.files[modpath] = path
        self.text[path] = text
        base = os.path.dirname(path)
        if not (path.endswith("mod.rs") or path.endswith("lib.rs") or path.endswith("main.rs")):
            base = os.path.join(base, os.path.splitext(os.path.basename(path))[0])
        for m in MOD_DECL.findall(text):
            if m == "tests":
                continue
            for cand in (os.path.join(base, m + ".rs"), os.path.join(base, m, "mod.rs")):
                if os.path.exists(cand):
                    self.load(modpath + (m,), cand)
                    break

    def items(self, path):
        text = self.text[path]
        names = {m[1] for m in ITEM.findall(text)}
        names |= set(INLINE_MOD.findall(text))
        return names

    def reexports(self, path):
        """name -> absolute path segments it re-exports (from `pub use`)."""
        out = {}
        modpath = self.modpath_of(path)
        for vis, tree in USE.findall(self.text[path]):
            if not vis:
                continue
            for segs in expand(tree):
                absolute = self.absolutize(modpath, segs)
                if absolute:
                    out[segs[-1]] = absolute
        return out

    def modpath_of(self, path):
        for k, v in self.files.items():
            if v == path:
                return k
        raise KeyError(path)

    def absolutize(self, modpath, segs):
        if not segs:
            return None
        if segs[0] == "crate":
            return list(segs[1:])
        if segs[0] == "self":
            return list(modpath) + list(segs[1:])
        if segs[0] == "super":
            mp = list(modpath)
            i = 0
            while i < len(segs) and segs[i] == "super":
                if mp:
                    mp.pop()
                i += 1
            return mp + list(segs[i:])
        # a path relative to the current module (`use child::X` in 2018 edition)
        if tuple(modpath) + (segs[0],) in self.files:
            return list(modpath) + list(segs)
        return None  # external crate or std

    def resolve(self, absolute, depth=0):
        """The file defining the item at `absolute` (a module path + optional item name)."""
        if depth > 20:
            return None
        mp = ()
        i = 0
        while i < len(absolute) and mp + (absolute[i],) in self.files:
            mp = mp + (absolute[i],)
            i += 1
        path = self.files[mp]
        if i == len(absolute):
            return None  # a whole module named: `use crate::x;` is resolved at its uses
        name = absolute[i]
        if name == "*" or name in self.items(path):
            return path
        target = self.reexports(path).get(name)
        if target:
            return self.resolve(target + absolute[i + 1 :], depth + 1)
        return path

    def edges(self):
        out = {}
        for mp, path in self.files.items():
            if os.path.basename(path) == "tests.rs" or "tests" in mp:
                continue
            deps = set()
            text = self.text[path]
            paths = []
            for vis, tree in USE.findall(text):
                if vis:
                    continue  # a re-export is a facade, followed at resolution
                paths += expand(tree)
            body = USE.sub("", text)
            paths += [p.split("::") for p in INLINE_PATH.findall(body)]
            # module aliases introduced by `use crate::x::y;` then `y::f()`
            aliases = {}
            for vis, tree in USE.findall(text):
                for segs in expand(tree):
                    absolute = self.absolutize(mp, segs)
                    if absolute and tuple(absolute) in self.files:
                        aliases[segs[-1]] = absolute
            # child modules named relative to this one (`convert::run(...)` in a mod.rs)
            for child in [k[-1] for k in self.files if len(k) == len(mp) + 1 and k[:-1] == mp]:
                aliases.setdefault(child, list(mp) + [child])
            for alias, absolute in aliases.items():
                for m in re.finditer(r"(?<![A-Za-z0-9_:])" + re.escape(alias) + r"::([A-Za-z_][A-Za-z0-9_]*)", body):
                    paths.append(["crate"] + absolute + [m.group(1)])
            for segs in paths:
                absolute = self.absolutize(mp, segs)
                if absolute is None:
                    continue
                target = self.resolve(absolute)
                if target and target != path and os.path.basename(target) != "tests.rs":
                    deps.add(target)
            out[path] = deps
        return out


def cycles(edges):
    """Strongly connected components with more than one file (Tarjan)."""
    index, low, stack, on, comps = {}, {}, [], set(), []
    counter = [0]

    def visit(v):
        index[v] = low[v] = counter[0]
        counter[0] += 1
        stack.append(v)
        on.add(v)
        for w in edges.get(v, ()):
            if w not in index:
                visit(w)
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
                comps.append(sorted(comp))

    sys.setrecursionlimit(10000)
    for v in sorted(edges):
        if v not in index:
            visit(v)
    return comps


def main():
    root = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
    srcs = sys.argv[1:] or (
        [os.path.join("crates", c, "src") for c in sorted(os.listdir(os.path.join(root, "crates")))
         if os.path.exists(os.path.join(root, "crates", c, "src"))] + ["src"]
    )
    bad = 0
    for src in srcs:
        src_abs = os.path.join(root, src) if not os.path.isabs(src) else src
        if os.path.basename(src_abs) != "src":
            src_abs = os.path.join(src_abs, "src")
        crate = Crate(src_abs)
        edges = crate.edges()
        comps = cycles(edges)
        rel = lambda p: os.path.relpath(p, root)
        n_edges = sum(len(v) for v in edges.values())
        if comps:
            bad += len(comps)
            for comp in comps:
                print(f"circle in {rel(src_abs)}: " + " <-> ".join(rel(p) for p in comp))
                for p in comp:
                    back = sorted(rel(q) for q in edges[p] if q in comp)
                    print(f"    {rel(p)} uses {', '.join(back)}")
        else:
            print(f"{rel(src_abs)}: {len(edges)} files, {n_edges} imports between them, no circle")
    sys.exit(1 if bad else 0)


if __name__ == "__main__":
    main()
