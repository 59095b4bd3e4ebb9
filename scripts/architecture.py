#!/usr/bin/env python3
"""Checks ARCHITECTURE.md's two tables against the code, so they cannot drift.

    python3 scripts/architecture.py

* **The crates**: one row per workspace member, its folder, and in the last
  column exactly the gpodo crates its `Cargo.toml` lists under
  `[dependencies]` (short names, comma-separated, or `nothing`;
  parenthesised notes such as feature-gated crates are ignored).
* **Large files**: exactly the source files (`*/src/**/*.rs`, `tests.rs`
  files and `tests/` folders apart) over 500 lines, each at its line count.

Prints every disagreement and exits 1 if there is any.
"""

import re
import sys
import tomllib
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
LIMIT = 500


def rows(text: str, heading: str):
    """The body rows of the first Markdown table after `heading`."""
    after = text[text.index(heading) :]
    table = []
    for line in after.splitlines()[1:]:
        if line.startswith("|"):
            table.append([c.strip() for c in line.strip("|").split("|")])
        elif table:
            break
    return table[2:]


def check_crates(text: str):
    problems = []
    workspace = tomllib.loads((ROOT / "Cargo.toml").read_text())
    members = workspace["workspace"]["members"]
    table = {r[0].strip("`"): r for r in rows(text, "## The crates")}
    for folder in members:
        manifest = tomllib.loads((ROOT / folder / "Cargo.toml").read_text())
        name = manifest["package"]["name"]
        row = table.pop(name, None)
        if row is None:
            problems.append(f"the crate table has no row for `{name}` ({folder}/)")
            continue
        if row[1].strip("`").rstrip("/") != folder:
            problems.append(f"`{name}`: folder {row[1]}, expected `{folder}/`")
        written = re.sub(r"\([^)]*\)", "", row[-1])
        written = {w.strip() for w in written.split(",") if w.strip()} - {"nothing"}
        actual = {
            d.removeprefix("gpodo-")
            for d in manifest.get("dependencies", {})
            if d.startswith("gpodo-")
        }
        if written != actual:
            problems.append(
                f"`{name}` depends on {', '.join(sorted(actual)) or 'nothing'}; the table says {row[-1]}"
            )
    for name in table:
        problems.append(f"the crate table has a row for `{name}`, which is not a workspace member")
    return problems


def large_files():
    found = {}
    for file in ROOT.glob("*/src/**/*.rs"):
        relative = file.relative_to(ROOT)
        if file.name == "tests.rs" or "tests" in relative.parts[2:-1]:
            continue
        lines = len(file.read_text(encoding="utf-8").splitlines())
        if lines > LIMIT:
            found[str(relative)] = lines
    return found


def check_large_files(text: str):
    problems = []
    table = {r[0].strip("`"): int(r[1]) for r in rows(text, "**Large files.**")}
    for path, lines in sorted(large_files().items()):
        if path not in table:
            problems.append(f"`{path}` has {lines} lines and is not in the large-files table")
        elif table[path] != lines:
            problems.append(f"`{path}` has {lines} lines; the table says {table[path]}")
    for path in sorted(set(table) - set(large_files())):
        problems.append(f"the large-files table lists `{path}`, which is not over {LIMIT} lines")
    return problems


def main():
    text = (ROOT / "ARCHITECTURE.md").read_text(encoding="utf-8")
    problems = check_crates(text) + check_large_files(text)
    for p in problems:
        print("ARCHITECTURE.md: " + p)
    print(f"ARCHITECTURE.md: {len(problems)} disagreements with the code")
    return 1 if problems else 0


if __name__ == "__main__":
    sys.exit(main())
