#!/usr/bin/env python3
"""The tail of a back-end's step times on every graph (backends/aprilsam/TAIL.md).

Runs hamal_bench under the thesis protocol (its defaults: the cholesky batch
optimum as reference) once per graph with --rows and --summary, and writes
DIR/tail.csv and DIR/tail.md: per graph and back-end the poses, the step
times' p50/p90/p99/max, the batches, chi2/opt, the steps over --limit_ms and
what they were (full batch, top re-elimination, incremental step), and the
load average before the run (times on a loaded machine are inflated; the
counts are not). A graph is a file, NAME=FILE, or gen:N (hamal_generate's
world of N poses, seed 1, its defaults), each optionally followed, in the
same argument, by hamal_bench flags for it alone ("w20000.txt --format=gtsam
--init=lago": its EDGE2 lines are covariances, and the reference batch from
odometry stalls far from its optimum, docs/PROTOCOL.md; from LAGO the
reference takes more than cholesky's 20 iterations).

  scripts/step_tail.py [--dir results/step_tail] [--backend aprilsam-top]
                       [--build build] [--limit_ms 10] [GRAPH ...]

A graph whose DIR/<name>/summary.csv exists is not run again, so an
interrupted run resumes where it stopped; delete that folder to redo one.
--tables_only re-reads DIR without running anything.
"""
import argparse
import csv
import os
import shutil
import subprocess
import sys

DATA = os.environ.get("HAMAL_DATA_DIR", "../shared/data")
JUDGING = "/work/judging"
DEFAULT_GRAPHS = ([os.path.join(DATA, f) for f in
                   ("CSAIL.g2o", "intel.g2o", "M3500.toro", "manhattan.g2o", "city10000.g2o",
                    "w20000.txt --format=gtsam --init=lago --reference=cholesky:max_iterations=100")] +
                  [os.path.join(JUDGING, f) for f in
                   ("MIT.g2o", "kitti_05.g2o", "kitti_00.g2o", "kitti_02.g2o", "ais2klinik.g2o")] +
                  ["gen:10000", "gen:20000"])


def kind_of(row):
    """Full batch, top re-elimination (a batch decision that re-eliminated
    only the top: kind incremental, reason "... top re-eliminated") or an
    incremental step."""
    if row["kind"] == "batch":
        return "batch"
    if "top re-eliminated" in row["reason"]:
        return "top"
    return "incr"


def graph_name(spec):
    spec = spec.split()[0]
    if "=" in spec:
        return spec.split("=", 1)[0]
    if spec.startswith("gen:"):
        return "gen" + spec[4:]
    return os.path.basename(spec).split(".")[0]


def tail_of(rows_path, limit_s):
    """Per back-end: the steps over limit_s by kind, and the slowest step."""
    out = {}
    with open(rows_path) as f:
        for row in csv.DictReader(f):
            if row.get("run", "0") not in ("0", ""):
                continue  # first run only: --repeat runs are the same steps
            t = out.setdefault(row["backend"], {"batch": 0, "top": 0, "incr": 0, "worst": None})
            s = float(row["seconds"])
            if s > limit_s:
                t[kind_of(row)] += 1
            if t["worst"] is None or s > float(t["worst"]["seconds"]):
                t["worst"] = row
    return out


def run(args, spec, out):
    """One hamal_bench invocation into out (through out.partial)."""
    tmp = out + ".partial"
    shutil.rmtree(tmp, ignore_errors=True)
    os.makedirs(tmp)
    spec, flags = spec.split()[0], spec.split()[1:]
    data = spec.split("=", 1)[1] if "=" in spec else spec
    if spec.startswith("gen:"):
        data = os.path.join(tmp, graph_name(spec) + ".g2o")
        subprocess.run([os.path.join(args.build, "apps", "hamal_generate"), "--poses", spec[4:],
                        "--seed", "1", "--output", data], check=True, stdout=subprocess.DEVNULL)
    with open(os.path.join(tmp, "load.txt"), "w") as f:
        f.write("{:.2f}\n".format(os.getloadavg()[0]))
    cmd = [os.path.join(args.build, "apps", "hamal_bench"), "--data", data, "--backend",
           args.backend, "--chi2_every", "0", "--rows", os.path.join(tmp, "rows.csv"),
           "--summary", os.path.join(tmp, "summary.csv")] + flags + args.bench_args
    with open(os.path.join(tmp, "log.txt"), "w") as log:
        log.write(" ".join(cmd) + "\n")
        log.flush()
        subprocess.run(cmd, check=True, stdout=log, stderr=subprocess.STDOUT)
    if spec.startswith("gen:"):
        os.remove(data)  # remade in a second from the seed
    os.rename(tmp, out)


def collect(args, names):
    lines = []
    limit_s = args.limit_ms / 1e3
    for name in names:
        out = os.path.join(args.dir, name)
        with open(os.path.join(out, "load.txt")) as f:
            load = f.read().strip()
        tails = tail_of(os.path.join(out, "rows.csv"), limit_s)
        with open(os.path.join(out, "summary.csv")) as f:
            for s in csv.DictReader(f):
                t = tails[s["backend"]]
                w = t["worst"]
                lines.append({
                    "graph": name, "backend": s["backend"], "poses": int(s["steps"]),
                    "p50_ms": 1e3 * float(s["p50_seconds"]), "p90_ms": 1e3 * float(s["p90_seconds"]),
                    "p99_ms": 1e3 * float(s["p99_seconds"]), "max_ms": 1e3 * float(s["max_seconds"]),
                    "total_s": float(s["cumulative_seconds"]), "batches": int(s["batch_steps"]),
                    "chi2_opt": float(s["chi2_ratio"]) if s["chi2_ratio"] else float("nan"),
                    "over_batch": t["batch"], "over_top": t["top"], "over_incr": t["incr"],
                    "worst_kind": kind_of(w), "worst_columns": int(w["columns_recomputed"] or 0),
                    "load": float(load)})
    return lines


FIELDS = ["graph", "backend", "poses", "p50_ms", "p90_ms", "p99_ms", "max_ms", "total_s",
          "batches", "chi2_opt", "over_batch", "over_top", "over_incr", "worst_kind",
          "worst_columns", "load"]


def markdown(lines, limit_ms):
    head = ("| graph | poses | p50 ms | p90 ms | p99 ms | max ms | total s | batches | chi2/opt | "
            "> {0:g} ms: batch / top / incr | slowest step (columns) | load |".format(limit_ms))
    several = len({l["backend"] for l in lines}) > 1
    if several:
        head = "| back-end " + head
    md = [head, "|" + "---|" * head.count(" | ") + "---|"]
    for l in lines:
        cells = [l["graph"], str(l["poses"])] + ["{:.2f}".format(l[k]) for k in
                                                   ("p50_ms", "p90_ms", "p99_ms", "max_ms")]
        cells += ["{:.1f}".format(l["total_s"]), str(l["batches"]), "{:.6f}".format(l["chi2_opt"]),
                  "{} / {} / {}".format(l["over_batch"], l["over_top"], l["over_incr"]),
                  "{} ({})".format(l["worst_kind"], l["worst_columns"]), "{:.1f}".format(l["load"])]
        if several:
            cells.insert(0, l["backend"])
        md.append("| " + " | ".join(cells) + " |")
    return "\n".join(md) + "\n"


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("graphs", nargs="*", default=DEFAULT_GRAPHS)
    ap.add_argument("--dir", default="results/step_tail")
    ap.add_argument("--backend", default="aprilsam-top")
    ap.add_argument("--build", default="build")
    ap.add_argument("--limit_ms", type=float, default=10.0)
    ap.add_argument("--tables_only", action="store_true")
    ap.add_argument("--bench_args", nargs="*", default=[],
                    help="further hamal_bench flags, e.g. --bench_args=--residual=measurement")
    args = ap.parse_args()
    os.makedirs(args.dir, exist_ok=True)
    names = []
    for spec in args.graphs:
        name = graph_name(spec)
        out = os.path.join(args.dir, name)
        if not args.tables_only and not os.path.exists(os.path.join(out, "summary.csv")):
            print("running {}...".format(name), file=sys.stderr)
            run(args, spec, out)
        if os.path.exists(os.path.join(out, "summary.csv")):
            names.append(name)
    lines = collect(args, names)
    with open(os.path.join(args.dir, "tail.csv"), "w", newline="") as f:
        w = csv.DictWriter(f, FIELDS)
        w.writeheader()
        w.writerows(lines)
    md = markdown(lines, args.limit_ms)
    with open(os.path.join(args.dir, "tail.md"), "w") as f:
        f.write(md)
    print(md, end="")


if __name__ == "__main__":
    main()
