#!/usr/bin/env python3
"""Compare two results folders of `gpodo run`, file by file, ignoring only
what is not meant to repeat: wall-clock times and the code version.

    python3 experiments/scripts/compare_results.py results-before/paper results/paper

Every file must exist on both sides. JSON and JSON-lines files are compared
as values after dropping the keys `duration_secs`, `cpu_secs`, `code_version` and
`timing`; Markdown after blanking the code version, the wall and CPU
times and the `fit [s]` (`fit wall [s]`) column; every other file (CSV, TUM, SVG) byte for byte. Exits 1
and names the first differences when the folders differ.

    python3 experiments/scripts/compare_results.py --hyperopt-keys OLD NEW

also maps the resolved configuration of a gpodo from before the GPs'
`hyperopt:` block (OLD) to the new key names: an exact or sparse GP's
flat optimiser settings (`max_iters`, `bounds`, ...) are compared as
`hyperopt.max_iters`, `hyperopt.bounds`, ...
"""

import json
import re
import sys
from pathlib import Path

VOLATILE_KEYS = {"duration_secs", "cpu_secs", "code_version", "timing"}
VOLATILE_COLUMNS = {"fit [s]", "fit wall [s]"}
HYPEROPT_FIELDS = ["optimizer", "max_iters", "start", "restarts", "gradient_tolerance",
                   "relative_cost_tolerance", "lbfgs_memory", "bounds"]


def nest_hyperopt(value):
    """A GP's flat optimiser settings moved into its `hyperopt` block."""
    if isinstance(value, list):
        return [nest_hyperopt(v) for v in value]
    if not isinstance(value, dict):
        return value
    value = {k: nest_hyperopt(v) for k, v in value.items()}
    if value.get("kind") in ("exact_gp", "sparse_gp") and "hyperopt" not in value:
        moved = {k: value.pop(k) for k in HYPEROPT_FIELDS if k in value}
        if moved:
            value["hyperopt"] = moved
    return value


def scrub(value):
    if isinstance(value, dict):
        return {k: scrub(v) for k, v in value.items() if k not in VOLATILE_KEYS}
    if isinstance(value, list):
        return [scrub(v) for v in value]
    return value


def markdown(text):
    text = re.sub(r"Code: `[^`]*`", "Code: `…`", text)
    text = re.sub(r"code `[^`]*`", "code `…`", text)
    text = re.sub(r"Wall time: [0-9.]+ s", "Wall time: … s", text)
    text = re.sub(r"CPU time: [0-9.]+ s", "CPU time: … s", text)
    out, blank = [], set()
    for line in text.splitlines():
        if line.startswith("|"):
            # A cell may hold an escaped pipe (`\|residual\|`).
            cells = re.split(r"(?<!\\)\|", line.strip("|"))
            names = [c.strip() for c in cells]
            if VOLATILE_COLUMNS & set(names):
                blank = {i for i, n in enumerate(names) if n in VOLATILE_COLUMNS}
            elif blank and not set(line) <= set("|-: "):
                cells = ["…" if i in blank else c for i, c in enumerate(cells)]
                line = "|" + "|".join(cells) + "|"
        else:
            blank = set()
        out.append(line)
    return "\n".join(out)


def normalised(path, mapping=lambda v: v):
    if path.suffix == ".json":
        return mapping(scrub(json.loads(path.read_text())))
    if path.suffix == ".jsonl":
        # Parallel runs append their records in the order they finish:
        # compare them by key.
        records = [mapping(scrub(json.loads(l))) for l in path.read_text().splitlines() if l]
        return sorted(records, key=lambda r: json.dumps(r.get("key"), sort_keys=True))
    if path.suffix == ".md":
        return markdown(path.read_text())
    return path.read_bytes()


def main(before, after, mapping=lambda v: v):
    a = {p.relative_to(before) for p in before.rglob("*") if p.is_file()}
    b = {p.relative_to(after) for p in after.rglob("*") if p.is_file()}
    problems = [f"only in {before}: {p}" for p in sorted(a - b)]
    problems += [f"only in {after}: {p}" for p in sorted(b - a)]
    for rel in sorted(a & b):
        if normalised(before / rel, mapping) != normalised(after / rel):
            problems.append(f"differs: {rel}")
    for p in problems[:40]:
        print(p)
    print(f"{len(a & b)} files compared, {len(problems)} difference(s)")
    return 1 if problems else 0


if __name__ == "__main__":
    args = sys.argv[1:]
    mapping = lambda v: v
    if args[:1] == ["--hyperopt-keys"]:
        args, mapping = args[1:], nest_hyperopt
    if len(args) != 2:
        sys.exit(__doc__)
    sys.exit(main(Path(args[0]), Path(args[1]), mapping))
