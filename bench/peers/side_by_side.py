#!/usr/bin/env python3
"""GPy and gpodo's exact GP timed side by side, one command for the whole peer table.

For every row (a table, its first N rows and first D inputs) the script
writes the standardised data once (`fit_peers.py --write-data`), then runs
the two fits in alternation, gpodo first (A B A B ...), each as its own
process under `/usr/bin/time -v`:

* gpodo: `fit_csv FILE` (the `gpodo-regressors` example; build it first with
  `cargo build --release -p gpodo-regressors --example fit_csv`), its default
  start policy;
* GPy: `fit_peers.py --peers gpy` on the same rows (start: lengthscales
  sqrt(D)), or, for the ExoTeR split of Table I (`exoter`), `exoter_table1.py
  --kernels rbf` (GPy's own start) beside `fit_csv` on the first 1869 rows.

Each run's JSON line goes to `--out` (with the process's wall seconds and
peak resident memory added as "process_seconds" and "peak_mib"); at the end a
markdown table with the medians is printed: each fit's own time ("fit s",
as the script printed it), evaluations and LML, the ratio of the fit times'
medians, the median of the per-pair ratios of whole-process wall time, the
per-evaluation ratio and the peak memory. The rows of bench/README.md
("Peers side by side"):

    python bench/peers/side_by_side.py --rows 500x18,500x28,1000x18,1000x28 --warmup 1 --pairs 3
    python bench/peers/side_by_side.py --rows 2000x18,2000x28,exoter --pairs 1
    cargo run --release -p gpodo-experiments -- run experiments/peer-table-sim.yaml  # 4000 rows
    python bench/peers/side_by_side.py --rows 4000x28,4000x18 --pairs 1 --sim

Run it on an otherwise idle machine: the two fits share its cores in turn.
"""

import argparse
import json
import re
import statistics
import subprocess
import sys
from pathlib import Path

HERE = Path(__file__).resolve().parent
REPO_ROOT = HERE.parents[1]
FIT_CSV = REPO_ROOT / "target" / "release" / "examples" / "fit_csv"
SIM_TABLE = REPO_ROOT / "results" / "peer-table-sim" / "residuals_train.csv"
SIM_TARGETS = "res_vx,res_vy,res_vz"
# The ExoTeR split of Table I: the first 80 % of the authors' 2337 rows.
EXOTER_TRAIN_ROWS = 1869


def timed(command):
    """Runs `command` under /usr/bin/time -v; its last JSON line on stdout,
    with the process's wall seconds and peak resident memory."""
    proc = subprocess.run(["/usr/bin/time", "-v", *map(str, command)], cwd=REPO_ROOT,
                          capture_output=True, text=True)
    if proc.returncode != 0:
        sys.exit(f"{' '.join(map(str, command))} failed ({proc.returncode}):\n{proc.stderr[-2000:]}")
    lines = [line for line in proc.stdout.splitlines() if line.startswith("{")]
    if not lines:
        sys.exit(f"{' '.join(map(str, command))} printed no JSON line")
    out = json.loads(lines[-1])
    wall = re.search(r"Elapsed \(wall clock\) time \(h:mm:ss or m:ss\): (\S+)", proc.stderr)
    rss = re.search(r"Maximum resident set size \(kbytes\): (\d+)", proc.stderr)
    if wall is None or rss is None:
        sys.exit("/usr/bin/time -v printed no wall time or peak memory")
    seconds = 0.0
    for part in wall.group(1).split(":"):
        seconds = 60.0 * seconds + float(part)
    out.update(process_seconds=seconds, peak_mib=int(rss.group(1)) / 1024.0)
    return out


def row_commands(row, args, data_dir):
    """The row's label and its gpodo and GPy commands (the data written first)."""
    python = sys.executable
    if row == "exoter":
        n, d, table = EXOTER_TRAIN_ROWS, 28, []
        gpy = [python, HERE / "exoter_table1.py", "--kernels", "rbf"]
        label = "ExoTeR split, rbf"
    else:
        match = re.fullmatch(r"(\d+)x(\d+)", row)
        if match is None:
            sys.exit(f"a row is NxD or exoter, found {row!r}")
        n, d = int(match.group(1)), int(match.group(2))
        table = ["--table", SIM_TABLE, "--targets", SIM_TARGETS] if args.sim else []
        gpy = [python, HERE / "fit_peers.py", *table, "--n", n, "--d", d, "--peers", "gpy"]
        label = f"{n} / {d}" + (" simulated" if args.sim else "")
    data = data_dir / f"{'sim_' if table else ''}n{n}_d{d}.csv"
    write = [python, HERE / "fit_peers.py", *table, "--n", n, "--d", d, "--peers", "",
             "--write-data", data]
    subprocess.run([str(a) for a in write], cwd=REPO_ROOT, check=True, capture_output=True)
    return label, [args.fit_csv, data], gpy


def median(runs, key):
    return statistics.median(r[key] for r in runs)


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--rows", default="500x18,500x28,1000x18,1000x28",
                    help="comma list of NxD (first N rows, first D inputs) or exoter")
    ap.add_argument("--pairs", type=int, default=3, help="counted A B pairs per row")
    ap.add_argument("--warmup", type=int, default=0, help="uncounted pairs first")
    ap.add_argument("--sim", action="store_true",
                    help=f"rows from the simulated table {SIM_TABLE.relative_to(REPO_ROOT)}")
    ap.add_argument("--fit-csv", type=Path, default=FIT_CSV, help="the built fit_csv example")
    ap.add_argument("--data-dir", type=Path, default=Path("/tmp/peers"))
    ap.add_argument("--out", type=Path,
                    default=REPO_ROOT / "results" / "peers" / "side_by_side.jsonl",
                    help="every counted run's JSON line (appended; default under the "
                         "git-ignored results/)")
    args = ap.parse_args()
    if not args.fit_csv.exists():
        sys.exit(f"{args.fit_csv} not found: cargo build --release -p gpodo-regressors "
                 "--example fit_csv")
    if args.pairs < 1:
        sys.exit("--pairs must be at least 1")
    args.data_dir.mkdir(parents=True, exist_ok=True)
    args.out.parent.mkdir(parents=True, exist_ok=True)
    print("| row | GPy fit s (evals) | GPy LML | gpodo fit s (evals) | gpodo LML | fit × "
          "| process × | per evaluation × | peak MiB GPy / gpodo |")
    print("|---|---:|---:|---:|---:|---:|---:|---:|---:|")
    for row in [r.strip() for r in args.rows.split(",") if r.strip()]:
        label, gpodo_cmd, gpy_cmd = row_commands(row, args, args.data_dir)
        gpodo, gpy = [], []
        for k in range(args.warmup + args.pairs):
            a, b = timed(gpodo_cmd), timed(gpy_cmd)
            if k >= args.warmup:
                gpodo.append(a)
                gpy.append(b)
                with open(args.out, "a") as fh:
                    for r in (b, a):
                        fh.write(json.dumps(dict(r, row=row)) + "\n")
        g_fit, a_fit = median(gpy, "seconds"), median(gpodo, "seconds")
        g_evals, a_evals = gpy[0]["evaluations"], gpodo[0]["evaluations"]
        process = statistics.median(b["process_seconds"] / a["process_seconds"]
                                    for a, b in zip(gpodo, gpy))
        print(f"| {label} | {g_fit:.2f} ({g_evals}) | {gpy[0]['lml']:.2f} "
              f"| {a_fit:.2f} ({a_evals}) | {gpodo[0]['lml']:.2f} | {g_fit / a_fit:.1f} "
              f"| {process:.1f} | {(g_fit / g_evals) / (a_fit / a_evals):.1f} "
              f"| {median(gpy, 'peak_mib'):.0f} / {median(gpodo, 'peak_mib'):.0f} |",
              flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
