#!/usr/bin/env python3
"""Import circles between the source files of each crate of the workspace.

    python3 scripts/import_cycles.py

Each `.rs` file under a crate's `src/` is a module. A file imports another
when one of its `use` declarations or code paths (`crate::…`, `super::…`,
`self::…`; comments and doc comments apart) names that module or an item
in it. A module and its ancestors are not counted as importing each other:
a parent declares its children, and a child reaching up to its parent is
the module tree, not a circle. The script prints every set of files that
import each other in a circle (a strongly connected component of more
than one file) and exits 1 if there is any.
"""

import re
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent


def module_path(src: Path, file: Path):
    parts = list(file.relative_to(src).with_suffix("").parts)
    if parts[-1] in ("mod", "lib", "main"):
        parts = parts[:-1]
    return tuple(parts)


def expand(tree: str):
    """`a::{b, c::{d, e}}` → [`a::b`, `a::c::d`, `a::c::e`]."""
    tree = tree.strip()
    depth, start = 0, None
    for i, ch in enumerate(tree):
        if ch == "{":
            if depth == 0:
                start = i
            depth += 1
        elif ch == "}":
            depth -= 1
            if depth == 0:
                prefix, inner = tree[:start], tree[start + 1 : i]
                items, level, last = [], 0, 0
                for j, c in enumerate(inner):
                    if c == "{":
                        level += 1
                    elif c == "}":
                        level -= 1
                    elif c == "," and level == 0:
                        items.append(inner[last:j])
                        last = j + 1
                items.append(inner[last:])
                return [p for item in items if item.strip() for p in expand(prefix + item.strip())]
    return [tree.split(" as ")[0].strip()]


def references(text: str):
    code = "\n".join(line.split("//")[0] for line in text.splitlines())
    paths = []
    for m in re.finditer(r"\buse\s+([^;]*);", code):
        paths += expand(re.sub(r"\s+", "", m.group(1)).replace("as", " as "))
    paths += re.findall(r"\b(?:crate|super|self)(?:::\w+)+", code)
    return paths


def resolve(path: str, here, modules):
    parts = path.split("::")
    if parts[0] == "crate":
        base, rest = (), parts[1:]
    elif parts[0] in ("super", "self"):
        base = here
        while parts and parts[0] in ("super", "self"):
            if parts[0] == "super":
                base = base[:-1]
            parts = parts[1:]
        rest = parts
    else:
        return None
    target = base + tuple(rest)
    while target not in modules:
        if not target:
            return None
        target = target[:-1]
    return target


def cycles(src: Path):
    files = {module_path(src, f): f for f in src.rglob("*.rs")}
    edges = {m: set() for m in files}
    for m, f in files.items():
        for path in references(f.read_text(encoding="utf-8")):
            t = resolve(path, m, files)
            if t is None or t == m or t == m[: len(t)] or m == t[: len(m)]:
                continue
            edges[m].add(t)
    # Tarjan's strongly connected components.
    index, low, stack, on, out = {}, {}, [], set(), []

    def visit(v):
        index[v] = low[v] = len(index)
        stack.append(v)
        on.add(v)
        for w in edges[v]:
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in on:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            component = []
            while True:
                w = stack.pop()
                on.discard(w)
                component.append(w)
                if w == v:
                    break
            if len(component) > 1:
                out.append(sorted(str(files[c].relative_to(ROOT)) for c in component))

    sys.setrecursionlimit(10000)
    for v in edges:
        if v not in index:
            visit(v)
    return out


def main():
    found = []
    for manifest in sorted(ROOT.glob("*/Cargo.toml")):
        src = manifest.parent / "src"
        if src.is_dir():
            found += cycles(src)
    for component in found:
        print("import circle: " + " ↔ ".join(component))
    print(f"{len(found)} import circles")
    return 1 if found else 0


if __name__ == "__main__":
    sys.exit(main())
