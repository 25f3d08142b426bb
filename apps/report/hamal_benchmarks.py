#!/usr/bin/env python3
"""hamal_benchmarks: docs/BENCHMARKS.md, written from hamal_bench's JSON summaries.

The project's current figures (docs/PROTOCOL.md says how they are measured)
are not typed by hand: for each dataset this runs one hamal_bench over the
back-ends, under the thesis protocol, into RESULTS/<dataset>.json (the
bench's --summary) with RESULTS/<dataset>.provenance.json beside it (the
date, machine and git revision at the time of the run, and the command);
RESULTS is docs/benchmarks/, committed with the document,
and then writes the document from those files: one table per dataset, each
under the line saying when, where and at which commit it was measured.

A dataset whose two files exist is not run again, so a killed run resumes
with the next dataset, and --write_only redraws the document from what is
there. A dataset is a file name in --data_dir ("M3500.toro") or "gen<N>"
(hamal_bench --generate N, seed 1). Files that are absent are skipped,
saying so.

  python3 apps/report/hamal_benchmarks.py --bench build/apps/hamal_bench
  python3 apps/report/hamal_benchmarks.py --write_only      # the document only
"""

import argparse
import datetime
import json
import os
import shlex
import subprocess
import sys
import time

ROOT = os.path.abspath(os.path.join(os.path.dirname(__file__), "..", ".."))
sys.path.insert(0, os.path.join(ROOT, "apps", "sweep"))
import hamal_sweep  # noqa: E402  (git_revision, machine: recorded the same way as sweeps)
from old_spellings import old_spelling  # noqa: E402

DEFAULT_DATASETS = "M3500.toro,intel.g2o,manhattan.g2o,CSAIL.g2o,city10000.g2o"
DEFAULT_BACKENDS = "aprilsam;aprilsam-fullsolve;aprilsam-periodic;aprilsam-nopredictive;aprilsam-top"


def result_name(dataset):
    return dataset.replace("/", "_")


def bench_command(bench, dataset, data_dir, backends, repeat, summary):
    cmd = [bench]
    if dataset.startswith("gen") and dataset[3:].isdigit():
        cmd += ["--generate", dataset[3:], "--seed", "1"]
    else:
        cmd += ["--data", os.path.join(data_dir, dataset)]
    return cmd + ["--backend", backends, "--repeat", str(repeat), "--chi2_every", "0",
                  "--summary", summary]


def shown(arg):
    """A path inside or beside the checkout relative to it, so the recorded
    command reads the same on every machine."""
    if os.path.isabs(arg) and os.path.exists(arg):
        return os.path.relpath(arg, ROOT)
    return arg


def run_dataset(bench, dataset, data_dir, backends, repeat, results):
    """Runs one dataset unless its summary and provenance exist. Returns False
    when the dataset file is absent."""
    name = result_name(dataset)
    summary = os.path.join(results, name + ".json")
    provenance = os.path.join(results, name + ".provenance.json")
    if os.path.exists(summary) and os.path.exists(provenance):
        print(f"{dataset}: measured already ({summary})", flush=True)
        return True
    if not dataset.startswith("gen") and not os.path.exists(os.path.join(data_dir, dataset)):
        print(f"{dataset}: not in {data_dir}, skipped", flush=True)
        return False
    partial = os.path.join(results, name + ".partial.json")  # hamal_bench writes JSON for .json
    cmd = bench_command(bench, dataset, data_dir, backends, repeat, partial)
    print(f"{dataset}: running {' '.join(cmd)}", flush=True)
    started = datetime.datetime.now(datetime.timezone.utc)
    clock = time.monotonic()
    log_path = os.path.join(results, name + ".log")
    with open(log_path, "w") as log:
        done = subprocess.run(cmd, stdout=log, stderr=subprocess.STDOUT)
    if done.returncode != 0:
        sys.exit(f"{dataset}: hamal_bench failed (exit {done.returncode}), see {log_path}")
    info = {"dataset": dataset, "date": started.strftime("%Y-%m-%d %H:%M UTC"),
            "wall_seconds": round(time.monotonic() - clock, 1),
            "git_revision": hamal_sweep.git_revision(ROOT), "machine": hamal_sweep.machine(),
            "load_average": os.getloadavg()[0],
            "command": shlex.join(["hamal_bench"] + [shown(a) for a in cmd[1:-2]])}
    with open(provenance, "w") as f:
        json.dump(info, f, indent=1)
    os.replace(partial, summary)  # the summary last: its presence means complete
    print(f"{dataset}: done in {info['wall_seconds']} s", flush=True)
    return True


def fmt(value, digits):
    return "" if value is None else f"{value:.{digits}f}"


def table(rows):
    out = ["| back-end | steps | cumulative s | p50 ms | p99 ms | max ms | < 10 ms | batches "
           "| final chi2 | chi2/opt | not ok |",
           "|---|---|---|---|---|---|---|---|---|---|---|"]
    for r in rows:
        out.append("| " + " | ".join([
            r["backend"], str(r["steps"]), fmt(r["cumulative_seconds"], 3),
            fmt(1e3 * r["p50_seconds"], 2), fmt(1e3 * r["p99_seconds"], 2),
            fmt(1e3 * r["max_seconds"], 2), fmt(100 * r["share_under_10ms"], 1) + "%",
            str(r["batch_steps"]), fmt(r["final_chi2"], 5), fmt(r.get("chi2_ratio"), 6),
            str(r["non_ok_steps"])]) + " |")
    return "\n".join(out)


def provenance_line(info):
    m = info["machine"]
    return (f"Measured {info['date']} at commit `{info['git_revision']}` on {m['hostname']} "
            f"({m['cpu']}, {m['cores']} cores, load average {info['load_average']:.1f} at the "
            f"start), {info['wall_seconds']} s in all:\n\n    {info['command']}")


def write_document(results, datasets, out):
    parts = ["# Benchmarks",
             "",
             "Written by `scripts/benchmarks.sh` (apps/report/hamal_benchmarks.py) from "
             "hamal_bench's JSON summaries in `" + os.path.relpath(results, ROOT) + "`; do not "
             "edit by hand. Each table comes from one hamal_bench run under the thesis protocol "
             "([PROTOCOL.md](PROTOCOL.md)): only update calls are timed, times are medians over "
             "the runs the command asks for, chi2 is over the dataset's factors and chi2/opt "
             "divides it by the batch optimum of the reference back-end (cholesky) solved in the "
             "same run. Absolute times depend on the machine and its load, recorded with each "
             "table; compare back-ends within one table. What the project concluded from its "
             "earlier measurements is in [RECORD.md](RECORD.md).",
             ""]
    found = 0
    for dataset in datasets:
        name = result_name(dataset)
        summary = os.path.join(results, name + ".json")
        provenance = os.path.join(results, name + ".provenance.json")
        if not (os.path.exists(summary) and os.path.exists(provenance)):
            continue
        with open(summary) as f:
            rows = json.load(f)
        with open(provenance) as f:
            info = json.load(f)
        parts += [f"## {dataset}", "", provenance_line(info), "", table(rows), ""]
        found += 1
    if not found:
        sys.exit(f"no summaries in {results}: nothing to write")
    os.makedirs(os.path.dirname(os.path.abspath(out)), exist_ok=True)
    with open(out, "w") as f:
        f.write("\n".join(parts))
    print(f"wrote {out} ({found} dataset(s))", flush=True)


def main(argv=None):
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0],
                                formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--bench", default=os.path.join(ROOT, "build", "apps", "hamal_bench"))
    p.add_argument("--data_dir", default=os.environ.get(
        "HAMAL_DATA_DIR", os.path.join(ROOT, "..", "shared", "data")))
    p.add_argument("--datasets", default=DEFAULT_DATASETS,
                   help="comma-separated file names in --data_dir, or genN (default: %(default)s)")
    p.add_argument("--backend", dest="backends", default=DEFAULT_BACKENDS,
                   help="hamal_bench --backend (default: %(default)s)")
    old_spelling(p, "--backends", "--backend")
    p.add_argument("--repeat", type=int, default=3, help="runs per back-end; times are medians")
    p.add_argument("--results", default=os.path.join(ROOT, "docs", "benchmarks"),
                   help="where the summaries are kept (committed with the document)")
    p.add_argument("--output", dest="out", default=os.path.join(ROOT, "docs", "BENCHMARKS.md"))
    old_spelling(p, "--out", "--output")
    p.add_argument("--write_only", action="store_true",
                   help="write the document from the summaries already in --results")
    args = p.parse_args(argv)
    datasets = [d for d in args.datasets.split(",") if d]
    results = os.path.abspath(args.results)
    os.makedirs(results, exist_ok=True)
    if not args.write_only:
        if not os.access(args.bench, os.X_OK):
            sys.exit(f"no hamal_bench at {args.bench} (build first, or give --bench)")
        for i, dataset in enumerate(datasets):
            print(f"[{i + 1}/{len(datasets)}] ", end="", flush=True)
            run_dataset(args.bench, dataset, args.data_dir, args.backends, args.repeat, results)
    write_document(results, datasets, args.out)
    return 0


if __name__ == "__main__":
    sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "common"))
    import script_errors  # noqa: E402
    sys.exit(script_errors.run("hamal_benchmarks", main))
