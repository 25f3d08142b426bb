#!/usr/bin/env python3
"""Where AprilSAM's time goes as the map grows (backends/aprilsam/README.md).

Generates the scale study's worlds (hamal_generate, seed 1, the defaults
apps/sweep/specs/scale.json uses) at a few sizes, runs one back-end on each
under the thesis protocol with --rows, and prints a markdown table: per size,
the cumulative seconds of the three kinds of step (full batch, top
re-elimination, incremental), of each phase, the number of each kind and the
mean counts per step; then the fitted slope d log(total) / d log(n) of every
column. A column whose slope is over the total's is what grows.

  scripts/scale_profile.py [--sizes 5000,10000,20000,40000] [--dir /tmp/scale-profile]
                           [--backend aprilsam-top] [--build build] [--rows_only]

--rows_only re-reads DIR/gen<N>.g2o and DIR/rows<N>.csv without running anything.
"""
import argparse
import csv
import math
import os
import subprocess
import sys

PHASES = ["linearize", "order", "factor", "solve", "other"]


def kind_of(row):
    if row["kind"] == "batch":
        return "batch"
    if "top re-eliminated" in row["reason"]:
        return "top"
    return "incr"


def summarise(path):
    s = {"steps": 0}
    for k in ("batch", "top", "incr"):
        s[k + "_n"] = 0
        s[k + "_s"] = 0.0
        s[k + "_cols"] = 0
        s[k + "_relin"] = 0
    for p in PHASES:
        s[p] = 0.0
        for k in ("batch", "top", "incr"):
            s[k + "_" + p] = 0.0
    with open(path) as f:
        for row in csv.DictReader(f):
            k = kind_of(row)
            s["steps"] += 1
            s[k + "_n"] += 1
            s[k + "_s"] += float(row["seconds"])
            s[k + "_cols"] += int(row["columns_recomputed"] or 0)
            s[k + "_relin"] += int(row["variables_relinearized"] or 0)
            for p in PHASES:
                t = float(row[p + "_seconds"] or 0)
                s[p] += t
                s[k + "_" + p] = s.get(k + "_" + p, 0.0) + t
    s["total"] = s["batch_s"] + s["top_s"] + s["incr_s"]
    for k in ("batch", "top", "incr"):
        n = max(s[k + "_n"], 1)
        s[k + "_cols/step"] = s[k + "_cols"] / n
        s[k + "_ms/step"] = 1e3 * s[k + "_s"] / n
    return s


def closures(world):
    """Loop closures (edges between poses more than one step apart) and their
    mean gap in steps: the length of trajectory a closure corrects."""
    count, gaps = 0, 0
    with open(world) as f:
        for line in f:
            if line.startswith("EDGE"):
                gap = abs(int(line.split()[2]) - int(line.split()[1]))
                if gap > 1:
                    count += 1
                    gaps += gap
    return count, gaps / max(count, 1)


def slope(xs, ys):
    """Least-squares slope of log y against log x (None if a y is 0)."""
    if len(xs) < 2 or min(ys) <= 0:
        return None
    lx = [math.log(x) for x in xs]
    ly = [math.log(y) for y in ys]
    mx, my = sum(lx) / len(lx), sum(ly) / len(ly)
    sxx = sum((a - mx) ** 2 for a in lx)
    return sum((a - mx) * (b - my) for a, b in zip(lx, ly)) / sxx


# Two tables: the phases (over every step), then the kinds of step.
PHASE_COLUMNS = [("closures", "closures", "{}"), ("mean gap", "gap", "{:.0f}"),
                 ("total s", "total", "{:.2f}")] + [(p + " s", p, "{:.2f}") for p in PHASES]
KIND_COLUMNS = [
    ("batches", "batch_n", "{}"),
    ("batch s", "batch_s", "{:.2f}"),
    ("ms/batch", "batch_ms/step", "{:.0f}"),
    ("tops", "top_n", "{}"),
    ("top s", "top_s", "{:.2f}"),
    ("top factor s", "top_factor", "{:.2f}"),
    ("ms/top", "top_ms/step", "{:.1f}"),
    ("incr s", "incr_s", "{:.2f}"),
    ("incr factor s", "incr_factor", "{:.2f}"),
    ("incr solve s", "incr_solve", "{:.2f}"),
    ("ms/incr", "incr_ms/step", "{:.3f}"),
    ("cols/incr", "incr_cols/step", "{:.0f}"),
]


def table(sizes, sums, columns):
    lines = ["| poses | " + " | ".join(c[0] for c in columns) + " |",
             "|---:|" + "---:|" * len(columns)]
    for n, s in zip(sizes, sums):
        lines.append("| {} | ".format(n) + " | ".join(f.format(s[k]) for _, k, f in columns) + " |")
    cells = []
    for _, k, _ in columns:
        b = slope(sizes, [s[k] for s in sums])
        cells.append("-" if b is None else "{:.2f}".format(b))
    lines.append("| slope | " + " | ".join(cells) + " |")
    return "\n".join(lines)


def run(args, n):
    world = os.path.join(args.dir, "gen{}.g2o".format(n))
    rows = os.path.join(args.dir, "rows{}.csv".format(n))
    subprocess.run([os.path.join(args.build, "apps", "hamal_generate"), "--poses", str(n),
                    "--seed", "1", "--output", world], check=True, stdout=subprocess.DEVNULL)
    subprocess.run([os.path.join(args.build, "apps", "hamal_bench"), "--data", world,
                    "--backend", args.backend, "--chi2_every", "0", "--reference", "none",
                    "--rows", rows], check=True, stdout=subprocess.DEVNULL)
    return rows


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--sizes", default="5000,10000,20000,40000")
    ap.add_argument("--dir", default="/tmp/scale-profile")
    ap.add_argument("--backend", default="aprilsam-top")
    ap.add_argument("--build", default="build")
    ap.add_argument("--rows_only", action="store_true")
    args = ap.parse_args()
    sizes = [int(x) for x in args.sizes.split(",")]
    os.makedirs(args.dir, exist_ok=True)
    sums = []
    for n in sizes:
        rows = os.path.join(args.dir, "rows{}.csv".format(n))
        if not args.rows_only:
            print("running {} poses...".format(n), file=sys.stderr)
            rows = run(args, n)
        sums.append(summarise(rows))
        sums[-1]["closures"], sums[-1]["gap"] = closures(os.path.join(args.dir, "gen{}.g2o".format(n)))
    print(table(sizes, sums, PHASE_COLUMNS))
    print()
    print(table(sizes, sums, KIND_COLUMNS))


if __name__ == "__main__":
    main()
