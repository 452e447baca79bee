#!/usr/bin/env python3
"""Import circles inside each Rust crate of the workspace: file -> file edges from `use crate::...`,
`use super::...` and `crate::a::b` paths in code (test modules and comments left out), then the strongly
connected components of more than one file. Prints each circle; exits 1 if there is one.

Usage: python3 scripts/import_circles.py [REPO]   (default: the repository this script is in)
"""
import re
import sys
from pathlib import Path

ROOT = Path(sys.argv[1]) if len(sys.argv) > 1 else Path(__file__).resolve().parent.parent


def module_of(src: Path, f: Path) -> tuple:
    parts = list(f.relative_to(src).with_suffix("").parts)
    if parts[-1] in ("lib", "main", "mod"):
        parts = parts[:-1]
    return tuple(parts)


def code_of(text: str) -> str:
    text = text.split("#[cfg(test)]")[0]
    return "\n".join(line.split("//")[0] for line in text.splitlines())


def resolve(path: list, modules: dict):
    """The longest module prefix of `path` that is a file of the crate."""
    for n in range(len(path), -1, -1):
        if tuple(path[:n]) in modules:
            return modules[tuple(path[:n])]
    return None


def crate_edges(src: Path):
    files = [f for f in src.rglob("*.rs")]
    modules = {module_of(src, f): f for f in files}
    edges = {f: set() for f in files}
    for f in files:
        me = module_of(src, f)
        # `super` of a file is its parent module (of a mod.rs/lib.rs: the module above its folder's).
        parent = me[:-1]
        code = code_of(f.read_text())
        uses = re.findall(r"\buse\s+([^;]+);", code) + re.findall(r"\b((?:crate|super)(?:::\w+)+)", code)
        for u in uses:
            u = u.strip().replace("pub ", "")
            heads = []
            m = re.match(r"((?:crate|super)(?:::\w+)*)::\{(.*)\}$", u, re.S)
            if m:
                base = m.group(1)
                for item in m.group(2).split(","):
                    item = item.strip().split(" as ")[0].strip()
                    if item:
                        heads.append(base + "::" + item.split("::{")[0])
            else:
                heads.append(u.split(" as ")[0])
            for h in heads:
                p = h.split("::")
                if p[0] == "crate":
                    path = p[1:]
                elif p[0] == "super":
                    path = list(parent) + p[1:]
                else:
                    continue
                target = resolve(path, modules)
                if target is not None and target != f:
                    edges[f].add(target)
    return edges


def circles(edges: dict):
    index, low, stack, on, out, counter = {}, {}, [], set(), [], [0]

    def strong(v):
        index[v] = low[v] = counter[0]
        counter[0] += 1
        stack.append(v)
        on.add(v)
        for w in edges[v]:
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
    for v in edges:
        if v not in index:
            strong(v)
    return out


found = 0
for src in sorted(ROOT.glob("crates/*/src")):
    edges = crate_edges(src)
    for c in circles(edges):
        found += 1
        print(f"{src.parent.name}: " + " <-> ".join(str(f.relative_to(ROOT)) for f in c))
print(f"{found} import circle(s) inside a crate")
sys.exit(1 if found else 0)
