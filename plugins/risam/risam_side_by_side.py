#!/usr/bin/env python3
"""riSAM beside hamal's robust models on the same spoiled pose graphs
(plugins/risam/README.md): one invocation spoils the graphs (hamal_spoil),
runs hamal's incremental robust models (hamal_robust) and riSAM
(hamal_risam_native, graded by hamal_robust --estimate) on every file, and
writes RESULTS/side_by_side.csv (one row per run) and side_by_side.md (per
cell, over seeds).

Resumable: a run whose summary.json (or failed.json) is in RESULTS/runs is
not run again; a second call only redraws the tables (--redraw: from the
runs there, running none). Progress goes to stderr.

Every model runs at its default inlier threshold (the judging protocol of
apps/robust/README.md); --stated_thresholds gives hamal's GNC and PCM the
c2 that apps/sweep/specs/robust.json states for the dataset instead.

A dataset is a name of DATA below or a file in --data_dir, its ".g2o" left
off or not (the judging worlds of hamal_generate: --datasets sparse,drift).
N = 0 is the clean graph: one cell per dataset and seed, policy "clean".
--init lago grades against a clean optimum solved from LAGO's start, for a
graph whose batch solve from odometry does not converge (MIT).
A run is "right" as in hamal_robust_report.py: status ok, at most 1% of the
true loop closures rejected and of the false edges accepted, ATE at most
0.05 m.
"""
import argparse
import csv
import json
import math
import os
import subprocess
import sys
import time

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.normpath(os.path.join(HERE, "..", ".."))
sys.path.insert(0, os.path.join(ROOT, "apps", "robust"))
from hamal_robust_report import (RIGHT_ATE, RIGHT_FALSE_ACCEPTED,  # noqa: E402
                                 RIGHT_TRUE_REJECTED)

# (label, hamal_robust --backend), as apps/robust/README.md lists the incremental models.
HAMAL_MODELS = [
    ("aprilsam gnc", "aprilsam:robust=gnc"),
    ("aprilsam-top gnc", "aprilsam-top:robust=gnc"),
    ("aprilsam maxmix", "aprilsam:robust=maxmix"),
    ("aprilsam pcm+gnc", "aprilsam:robust=pcm+gnc"),
    ("aprilsam gnc group", "aprilsam:robust=gnc,gnc_group=on"),
]
RISAM = "riSAM"
RPGO = "Kimera-RPGO"  # with --rpgo: hamal_rpgo_native, graded as riSAM is
DATA = {"M3500": "M3500.toro", "intel": "intel.g2o", "CSAIL": "CSAIL.g2o",
        "manhattan": "manhattan.g2o", "city10000": "city10000.g2o"}


def data_file(data_dir, dataset):
    """The clean graph of a dataset: DATA's file, else the file so named in
    data_dir, else that name with ".g2o"."""
    path = os.path.join(data_dir, DATA.get(dataset, dataset))
    if dataset not in DATA and not os.path.isfile(path) and os.path.isfile(path + ".g2o"):
        path += ".g2o"
    return path


def cells_of(datasets, policies, outliers, seeds):
    """(dataset, policy, N, seed) in run order; N = 0 is one "clean" cell, whatever the
    policies (hamal_spoil writes the clean graph for any)."""
    cells = []
    for d in datasets:
        for pol in policies:
            for n in outliers:
                for s in seeds:
                    cell = (d, "clean" if n == 0 else pol, n, s)
                    if cell not in cells:
                        cells.append(cell)
    return cells


def right(r):
    """hamal_robust_report.py's "right" (its thresholds), on this script's records."""
    if r["status"] != "ok" or any(r.get(k) is None for k in ("ate", "true_off", "false_kept")):
        return False
    true_share = r["true_off"] / r["true_closures"] if r.get("true_closures") else 0
    false_share = r["false_kept"] / r["false_edges"] if r.get("false_edges") else 0
    return (true_share <= RIGHT_TRUE_REJECTED and false_share <= RIGHT_FALSE_ACCEPTED
            and r["ate"] <= RIGHT_ATE)


def percentile(samples, p):
    """apps/bench/percentiles.h: linear interpolation between closest ranks."""
    xs = sorted(samples)
    if not xs:
        return float("nan")
    h = (len(xs) - 1) * p / 100.0
    lo = math.floor(h)
    hi = min(lo + 1, len(xs) - 1)
    return xs[lo] + (h - lo) * (xs[hi] - xs[lo])


def step_seconds(rows_csv):
    with open(rows_csv, newline="") as f:
        return [float(r["seconds"]) for r in csv.DictReader(f)]


def run(cmd, timeout):
    """(returncode, output); returncode None on timeout."""
    try:
        p = subprocess.run(cmd, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True,
                           timeout=timeout)
        return p.returncode, p.stdout
    except subprocess.TimeoutExpired as e:
        out = e.stdout.decode() if isinstance(e.stdout, bytes) else (e.stdout or "")
        return None, out


def last_line(text):
    lines = [l for l in text.strip().splitlines() if l.strip()]
    return lines[-1] if lines else ""


def spoil(args, dataset, policy, n, seed):
    name = f"{dataset}-{policy}-{n}-s{seed}"
    out = os.path.join(args.results, "spoiled", name + ".g2o")
    if os.path.isfile(out) and os.path.isfile(out + ".false"):
        return name, out
    os.makedirs(os.path.dirname(out), exist_ok=True)
    code, text = run([os.path.join(args.bin_dir, "hamal_spoil"), "--data",
                      data_file(args.data_dir, dataset), "--outliers", str(n),
                      "--policy", "random" if policy == "clean" else policy, "--seed", str(seed),
                      "--output", out], None)
    if code != 0:
        raise SystemExit(f"risam_side_by_side: hamal_spoil failed on {dataset}:\n{text}")
    return name, out


def stated_threshold(dataset):
    with open(os.path.join(ROOT, "apps", "sweep", "specs", "robust.json")) as f:
        return json.load(f)["datasets"].get(dataset, {}).get("gnc_threshold")


def hamal_spec(spec, dataset, stated):
    c2 = stated_threshold(dataset) if stated else None
    if c2 is None:
        return spec
    extra = [f"{o}={c2:g}" for o, part in (("gnc_threshold", "gnc"), ("pcm_threshold", "pcm"))
             if part in spec.split("robust=")[1]]
    return spec + "".join("," + e for e in extra)


def run_one(args, spoiled, label, spec, out_dir):
    """Runs one model on one file into out_dir; returns its record."""
    robust = os.path.join(args.bin_dir, "hamal_robust")
    summary = os.path.join(out_dir, "summary.json")
    rows = os.path.join(out_dir, "rows.csv")
    grade = ["--summary", summary, "--diagnose_accepted=false", "--init", args.init,
             "--reference", args.reference]
    os.makedirs(out_dir, exist_ok=True)
    if spec in (None, RPGO):  # riSAM, RPGO: the harness, then hamal's grading of its files
        est, dec = os.path.join(out_dir, "estimate.g2o"), os.path.join(out_dir, "decisions.txt")
        harness = args.risam if spec is None else args.rpgo
        code, text = run([harness, "--data", spoiled, "--output", est, "--decisions", dec,
                          "--rows", rows], args.timeout)
        if code == 0:
            code, text = run([robust, "--data", spoiled, "--estimate", est, "--decisions", dec]
                             + grade, None)
    else:
        code, text = run([robust, "--data", spoiled, "--backend", spec, "--rows", rows,
                          "--chi2_every", "0"] + grade, args.timeout)
    if code != 0:
        failure = {"status": "timeout" if code is None else "crashed" if code < 0 else "failed",
                   "message": f"signal {-code}" if code is not None and code < 0
                   else last_line(text)}
        with open(os.path.join(out_dir, "failed.json"), "w") as f:
            json.dump(failure, f)
    return record(out_dir)


def record(out_dir):
    failed = os.path.join(out_dir, "failed.json")
    if os.path.isfile(failed):
        with open(failed) as f:
            return json.load(f)
    with open(os.path.join(out_dir, "summary.json")) as f:
        s = json.load(f)
    times = step_seconds(os.path.join(out_dir, "rows.csv"))
    status = s.get("status", "ok")
    if s.get("evaluation_error"):
        status = "not graded"
    return {"status": status, "ate": s.get("ate_translation"),
            "true_off": s.get("true_switched_off"), "false_kept": s.get("false_accepted"),
            "true_closures": s.get("true_loop_closures"), "false_edges": s.get("false_edges"),
            "seconds": sum(times), "p99_ms": 1e3 * percentile(times, 99)}


def fmt(x, digits=3):
    if x is None or (isinstance(x, float) and math.isnan(x)):
        return "-"
    if isinstance(x, int):
        return str(x)
    return f"{x:.{digits}g}"


def median(xs):
    xs = sorted(x for x in xs if x is not None)
    if not xs:
        return None
    m = len(xs) // 2
    return xs[m] if len(xs) % 2 else 0.5 * (xs[m - 1] + xs[m])


def tables(args, records):
    fields = ["dataset", "policy", "outliers", "seed", "model", "status", "ate_m", "true_off",
              "true_closures", "false_kept", "false_edges", "seconds", "p99_ms", "right"]
    with open(os.path.join(args.results, "side_by_side.csv"), "w", newline="") as f:
        w = csv.writer(f)
        w.writerow(fields)
        for (dataset, policy, n, seed, model), r in records:
            w.writerow([dataset, policy, n, seed, model, r["status"], r.get("ate"),
                        r.get("true_off"), r.get("true_closures"), r.get("false_kept"),
                        r.get("false_edges"), r.get("seconds"), r.get("p99_ms"), int(right(r))])
    cells = {}
    for (dataset, policy, n, seed, model), r in records:
        cells.setdefault((dataset, policy, n, model), []).append((seed, r))
    lines = ["| dataset | N | policy | model | seeds | status ok | ATE median (max) m "
             "| true off | false kept | time s | step p99 ms | right |",
             "|---|---|---|---|---|---|---|---|---|---|---|---|"]
    order = {m: i for i, m in enumerate([m for m, _ in HAMAL_MODELS] + [RISAM, RPGO])}
    for key in sorted(cells, key=lambda k: (k[0], k[2], k[1], order.get(k[3], 99))):
        dataset, policy, n, model = key
        rs = [r for _, r in cells[key]]
        ok = [r for r in rs if r["status"] == "ok"]
        graded = [r for r in rs if r.get("ate") is not None]
        ates = [r["ate"] for r in graded]
        ate = (f"{fmt(median(ates))} ({fmt(max(ates))})" if ates else "-")
        others = sorted({r["status"] for r in rs if r["status"] != "ok"})
        status = f"{len(ok)}/{len(rs)}" + (f" ({', '.join(others)})" if others else "")
        lines.append(
            f"| {dataset} | {n} | {policy} | {model} | {','.join(str(s) for s, _ in cells[key])} "
            f"| {status} | {ate} | {fmt(median([r.get('true_off') for r in graded]))} "
            f"| {fmt(median([r.get('false_kept') for r in graded]))} "
            f"| {fmt(median([r.get('seconds') for r in graded]))} "
            f"| {fmt(median([r.get('p99_ms') for r in graded]))} "
            f"| {sum(right(r) for r in rs)}/{len(rs)} |")
    note = ("Medians over the seeds listed; ATE in metres against the clean graph's least-squares "
            "optimum (hamal_robust); true off / false kept: true loop closures rejected, false "
            "edges accepted; time: the update calls (riSAM: RISAM2::update and calculateEstimate; "
            "Kimera-RPGO: RobustSolver::update and calculateEstimate); "
            f"thresholds: {'stated in robust.json' if args.stated_thresholds else 'defaults'}; "
            f"right: seeds with status ok, <= {RIGHT_TRUE_REJECTED:.0%} true off, "
            f"<= {RIGHT_FALSE_ACCEPTED:.0%} false kept, ATE <= {RIGHT_ATE:g} m.")
    text = "\n".join(lines) + "\n\n" + note + "\n"
    with open(os.path.join(args.results, "side_by_side.md"), "w") as f:
        f.write(text)
    print(text)


def main(argv=None):
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0],
                                formatter_class=argparse.RawDescriptionHelpFormatter,
                                epilog=__doc__.split("\n\n", 1)[1])
    p.add_argument("results")
    p.add_argument("--bin_dir", required=True, help="where hamal_spoil and hamal_robust are")
    p.add_argument("--risam", default=None,
                   help="the hamal_risam_native executable (needed when --models has riSAM)")
    p.add_argument("--rpgo", default=None,
                   help="the hamal_rpgo_native executable: Kimera-RPGO runs too")
    p.add_argument("--data_dir", default=os.path.join(ROOT, "..", "shared", "data"))
    p.add_argument("--datasets", default="intel,CSAIL,manhattan")
    p.add_argument("--policies", default="random,random-group")
    p.add_argument("--outliers", default="100")
    p.add_argument("--seeds", default="1,2")
    p.add_argument("--models", default=None,
                   help="comma-separated labels to run (default: all; 'riSAM' is riSAM)")
    p.add_argument("--stated_thresholds", action="store_true")
    p.add_argument("--reference", default="cholesky",
                   help="the back-end of the clean optimum every run is graded against "
                        "(hamal_robust --reference; w20000 needs more iterations than "
                        "cholesky's 20)")
    p.add_argument("--init", default="odometry", choices=["odometry", "lago"],
                   help="hamal_robust --init for every run's grading: where the clean graph's "
                   "batch optimum (the truth) starts; lago where odometry's does not converge "
                   "(MIT)")
    p.add_argument("--timeout", type=float, default=1800, help="seconds per run")
    p.add_argument("--redraw", action="store_true",
                   help="run nothing: draw the tables from the runs already in RESULTS")
    args = p.parse_args(argv)
    models = HAMAL_MODELS + [(RISAM, None)] + ([(RPGO, RPGO)] if args.rpgo else [])
    if args.models:
        keep = set(args.models.split(","))
        unknown = keep - {m for m, _ in models}
        if unknown:
            raise SystemExit(f"risam_side_by_side: unknown model(s) {sorted(unknown)}")
        models = [m for m in models if m[0] in keep]
    if (not args.redraw and any(spec is None for _, spec in models)
            and (args.risam is None or not os.access(args.risam, os.X_OK))):
        risam = args.risam or "--risam (not given)"
        raise SystemExit(f"risam_side_by_side: {risam} is not an executable "
                         "(plugins/risam/README.md says how to build it)")
    if (not args.redraw and any(spec == RPGO for _, spec in models)
            and not os.access(args.rpgo, os.X_OK)):
        raise SystemExit(f"risam_side_by_side: {args.rpgo} is not an executable "
                         "(plugins/risam/README.md says how to build it)")
    cells = cells_of(args.datasets.split(","), args.policies.split(","),
                     [int(n) for n in args.outliers.split(",")],
                     [int(s) for s in args.seeds.split(",")])
    total = len(cells) * len(models)
    records, k = [], 0
    for dataset, policy, n, seed in cells:
        name = f"{dataset}-{policy}-{n}-s{seed}"
        if not args.redraw:
            name, spoiled = spoil(args, dataset, policy, n, seed)
        for label, spec in models:
            k += 1
            out_dir = os.path.join(args.results, "runs", name, label.replace(" ", "_"))
            done = (os.path.isfile(os.path.join(out_dir, "summary.json"))
                    or os.path.isfile(os.path.join(out_dir, "failed.json")))
            if args.redraw and not done:
                continue
            start = time.time()
            if done:
                r = record(out_dir)
            else:
                full = (spec if spec in (None, RPGO)
                        else hamal_spec(spec, dataset, args.stated_thresholds))
                r = run_one(args, spoiled, label, full, out_dir)
            print(f"[{k}/{total}] {name} {label}: {r['status']}, ATE {fmt(r.get('ate'))} m, "
                  f"true off {fmt(r.get('true_off'))}, false kept {fmt(r.get('false_kept'))}"
                  + ("" if done else f" ({time.time() - start:.0f} s)")
                  + (f": {r['message']}" if r.get("message") else ""),
                  file=sys.stderr, flush=True)
            records.append(((dataset, policy, n, seed, label), r))
    tables(args, records)
    return 0


if __name__ == "__main__":
    sys.exit(main())
