#!/usr/bin/env python3
"""hamal_robust_sweep: the robust pose-graph benchmark's sweep (apps/robust/README.md).

Spoils every dataset of the spec with hamal_spoil (N false loop closures per
policy and seed; N = 0 once per dataset: the clean graph), then runs every
(loop-closure model x back-end) on every spoiled file through the house sweep
runner (apps/sweep/hamal_sweep.py) with hamal_robust as its bench, so the
results folder has the runner's layout and resumes as every sweep does:

  RESULTS/spoiled/<dataset>-<policy>-<N>-s<seed>.g2o (+ .false)   the inputs
  RESULTS/spoiled/config.json   the spoiling parameters; another spec's refused
  RESULTS/<dataset>-<policy>-<N>-s<seed>/<run-id>/                one run each
      summary.json (hamal_robust's graded result), rows.csv, config.json, log.txt
  RESULTS/manifest.json

The spec (apps/sweep/specs/robust.json):

  {"data_dir": "../../../../shared/data",
   "datasets": {"M3500": {"data": "M3500.toro"}, "CSAIL": {"data": "CSAIL.g2o", "init": "lago"}},
   "spoil": {"outliers": [0, 100, 1000],
             "policies": ["random", "local", "random-group", "local-group"],
             "seeds": [1, 2, 3, 4, 5], "group_size": 10, "local_window": 20},
   "models": ["none", "cauchy", "dcs", "maxmix", "gnc-tls", "gnc-gm", "pcm", "pcm+gnc"],
   "runs": [{"backend": "cholesky", "mode": "batch", "options": "max_iterations=100"},
            {"backend": "aprilsam", "mode": "incremental", "models": ["gnc"]},
            {"backend": "aprilsam", "mode": "incremental", "models": ["none"],
             "outliers": [0]},
            {"backend": "gtsam-gnc", "mode": "batch", "models": ["none"],
             "plugin": "plugins/libhamal_gtsam_plugin.so"}],
   "quick": [{"datasets": ["M3500"], "outliers": [0, 100], "seeds": [1],
              "models": ["none", "gnc-tls"], "backends": ["cholesky"]}],
   "reference": "cholesky", "timeout": 1800}

Every run kind crosses the spec's models, or its own "models" when it has
them, with every spoiled file, or only those whose N is in its own
"outliers". A run with a "plugin" (relative to the build directory, the
parent of --bin_dir) that is not built is skipped, and the skip written to
RESULTS/skipped.json for the report; a model the binary does not know fails
its runs, which the runner moves to RESULTS/failed with hamal_robust's
message. A dataset's "init" (odometry | lago) is the initial values of its
batch solves; its "gnc_threshold" (c2 > 0) the chi2 threshold of its models
where the chi2 quantile of the file's informations is not the data's: GNC's
inlier threshold (gnc_threshold), PCM's consistency threshold
(pcm_threshold), or the option a run names in "threshold_option" (gtsam-gnc's
"threshold"). The report's targets judge the runs at it; a run whose own
options set the option keeps its own.

  hamal_robust_sweep.py SPEC --results DIR [--jobs N] [--quick] [--datasets A,B]
      [--policies P,Q] [--outliers 0,100] [--models none,maxmix]
      [--backend cholesky,ceres] [--seeds 1,2,3] [--timeout S] [--dry_run]
      [--executor slurm --partition P --time T ...]  (hamal_sweep's executors)

--quick runs the spec's "quick" subsets, one sweep call each (one dataset,
policy and seed; a few models): a check that everything runs, in minutes.
The subset flags narrow the spec (or --quick's subsets) further.
--seeds replaces the spec's seeds
(any non-negative integers, not only the spec's); the report summarises
the seeds of a cell.
"""

import argparse
import json
import os
import subprocess
import sys

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.abspath(os.path.join(HERE, "..", ".."))
sys.path.insert(0, os.path.join(ROOT, "apps", "sweep"))
import atomic_json  # noqa: E402
import hamal_sweep  # noqa: E402
import resumable_results  # noqa: E402
from old_spellings import old_spelling  # noqa: E402


def load_spec(path):
    with open(path) as f:
        spec = json.load(f)
    base = os.path.dirname(os.path.abspath(path))
    data_dir = os.environ.get("HAMAL_DATA_DIR") or os.path.join(base, spec.get("data_dir", "."))
    for d in spec.get("datasets", {}).values():
        if not os.path.isabs(d["data"]):
            d["data"] = os.path.normpath(os.path.join(data_dir, d["data"]))
    return spec


def find_binary(name, given=None):
    for candidate in (given, os.path.join(ROOT, "build", "apps", name)):
        if candidate and os.path.exists(candidate):
            return os.path.abspath(candidate)
    raise SystemExit(f"hamal_robust_sweep: cannot find {name} (build it, or pass --bin_dir)")


def cells(spec, keep):
    """(dataset, policy, N, seed) of every spoiled file; N = 0 once per dataset."""
    sp = spec["spoil"]
    out = []
    for dname in spec["datasets"]:
        if keep["datasets"] and dname not in keep["datasets"]:
            continue
        for n in sp["outliers"]:
            if keep["outliers"] is not None and n not in keep["outliers"]:
                continue
            if n == 0:
                out.append((dname, "clean", 0, 0))
                continue
            for policy in sp["policies"]:
                if keep["policies"] and policy not in keep["policies"]:
                    continue
                for seed in sp.get("seeds", [1]):
                    out.append((dname, policy, n, seed))
    return out


def cell_name(dataset, policy, n, seed):
    return f"{dataset}-clean" if n == 0 else f"{dataset}-{policy}-{n}-s{seed}"


def spoiled_pair_done(out, n, seed, policy):
    """Whether a graph and its false-edge list are a complete pair of this cell:
    hamal_spoil writes both whole before it renames either, the list last, so a
    list beside the graph whose header names this spoiling and whose edge lines
    are its N makes the pair (hamal_robust checks the graph's factor count too)."""
    if not (os.path.exists(out) and os.path.exists(out + ".false")):
        return False
    spoiling, edges = {}, 0
    with open(out + ".false", encoding="utf-8", errors="replace") as f:
        for line in f:
            if line.startswith("# spoiling:"):
                spoiling = dict(item.partition("=")[::2] for item in line[11:].split())
            elif line.strip() and not line.startswith("#") and not line.startswith("factor"):
                edges += 1
    want = {"outliers": str(n), "seed": str(seed if n else 1)}
    if n:
        want["policy"] = policy
    return all(spoiling.get(k) == v for k, v in want.items()) and edges == n


def spoil(spoil_bin, spec, cell, results, dry_run):
    """The spoiled file of a cell, made once (spoiled_pair_done); a pair that is
    not complete (a list cut, or of another spoiling) is made again."""
    dataset, policy, n, seed = cell
    out = os.path.join(results, "spoiled", cell_name(*cell) + ".g2o")
    if spoiled_pair_done(out, n, seed, policy):
        return out
    sp = spec["spoil"]
    cmd = [spoil_bin, "--data", spec["datasets"][dataset]["data"],
           "--format", spec["datasets"][dataset].get("format", "auto"),
           "--outliers", str(n), "--policy", policy if n else "random",
           "--seed", str(seed if n else 1),
           "--group_size", str(sp.get("group_size", 10)),
           "--local_window", str(sp.get("local_window", 20)), "--output", out]
    if dry_run:
        print(" ".join(cmd), file=sys.stderr)
        return out
    os.makedirs(os.path.dirname(out), exist_ok=True)
    subprocess.run(cmd, check=True, stdout=subprocess.DEVNULL)
    return out


def check_spoil_parameters(spec, todo, results):
    """The spoiled files of a results folder are reused by name, so the
    parameters that made them are recorded in spoiled/config.json and a spec
    that would make them otherwise is refused, naming the parameter
    (apps/sweep/resumable_results.py)."""
    sp = spec["spoil"]
    parameters = {"group_size": sp.get("group_size", 10),
                  "local_window": sp.get("local_window", 20)}
    for dataset in sorted({c[0] for c in todo}):
        d = spec["datasets"][dataset]
        parameters[f"dataset {dataset}"] = {"data": d["data"], "format": d.get("format", "auto")}
    folder = os.path.join(results, "spoiled")
    made = os.path.isdir(folder) and any(f.endswith(".g2o") for f in os.listdir(folder))
    os.makedirs(folder, exist_ok=True)
    resumable_results.check_config(os.path.join(folder, "config.json"), parameters, made)


def run_models(spec, run):
    return run.get("models", spec["models"])


def stated_threshold(spec, dataset):
    """The inlier threshold c2 the spec states for a dataset's GNC models
    ("gnc_threshold"), or None: the default (the chi2 quantile at 0.99)."""
    value = spec["datasets"].get(dataset, {}).get("gnc_threshold")
    if value is None:
        return None
    if isinstance(value, bool) or not isinstance(value, (int, float)) or not value > 0:
        raise SystemExit(f"hamal_robust_sweep: dataset {dataset}: gnc_threshold must be a "
                         f"number > 0, not {value!r}")
    return float(value)


def threshold_options(run, model):
    """The options that carry a dataset's stated threshold to a run: GNC's
    gnc_threshold and PCM's pcm_threshold (both chi2 thresholds in the file's
    units), or the run's own "threshold_option" (gtsam-gnc's "threshold")."""
    if run.get("threshold_option"):
        return [run["threshold_option"]]
    return ([o for o, part in (("gnc_threshold", "gnc"), ("pcm_threshold", "pcm")) if part in model])


def plugin_path(run, bin_dir):
    """A run's plugin as hamal_sweep finds it: relative to the build directory."""
    plugin = run.get("plugin")
    if not plugin or os.path.isabs(plugin):
        return plugin
    return os.path.normpath(os.path.join(os.path.dirname(bin_dir), plugin))


def sweep_spec(spec, spoiled, keep, bin_dir, cells_of=None):
    """The hamal_sweep spec: one dataset per spoiled file, one group per run kind
    and model; and the notes of the runs skipped because their plugin is not built.
    cells_of: spoiled file name -> (dataset, policy, N, seed)."""
    cells_of = cells_of or {}
    datasets = {}
    for name, path in spoiled.items():
        datasets[name] = {"data": path, "format": "g2o"}
        source = spec["datasets"].get(cells_of.get(name, (name,))[0], {})
        if source.get("init"):
            datasets[name]["init"] = source["init"]
    groups, skipped = [], []
    for run in spec["runs"]:
        if keep["backends"] and run["backend"] not in keep["backends"]:
            continue
        models = [m for m in run_models(spec, run) if not keep["models"] or m in keep["models"]]
        # A run may be limited to some N (least squares incrementally: the clean file only).
        names = [n for n in datasets if "outliers" not in run
                 or cells_of.get(n, (n, "", 0, 0))[2] in run["outliers"]]
        if not models or not names:
            continue
        plugin = plugin_path(run, bin_dir)
        if plugin and not os.path.isfile(plugin):
            skipped.append({"backend": run["backend"], "mode": run.get("mode", "incremental"),
                            "models": models, "plugin": plugin,
                            "note": f"{run['backend']} skipped: its plugin {plugin} is not built "
                                    "(plugins/gtsam/README.md says how to build it)"})
            continue
        for model in models:
            # A GNC model runs at its dataset's stated inlier threshold, and
            # so does a run that names the option carrying it (gtsam-gnc's
            # "threshold"): one group per threshold. A run's own option wins.
            own = {o.partition("=")[0].strip() for o in run.get("options", "").split(",")}
            carriers = [o for o in threshold_options(run, model) if o not in own]
            by_threshold = {}
            for n in names:
                stated = None
                if carriers:
                    stated = stated_threshold(spec, cells_of.get(n, (n,))[0])
                by_threshold.setdefault(stated, []).append(n)
            for stated, here in by_threshold.items():
                options = [run["options"]] if run.get("options") else []
                if stated is not None:
                    options += [f"{o}={stated:g}" for o in carriers]
                group = {"name": "robust", "datasets": here,
                         "backends": [f"{run['backend']}:robust={model}"
                                      + "".join("," + o for o in options)],
                         "mode": run.get("mode", "incremental"), "chi2_every": 0,
                         "reference": spec.get("reference", "cholesky"),
                         "timeout": run.get("timeout", spec.get("timeout"))}
                if plugin:
                    group["plugin"] = plugin
                groups.append(group)
    return {"datasets": datasets, "groups": groups}, skipped




def csv_list(text, cast=str):
    return None if text is None else [cast(x) for x in text.split(",") if x]


def quick(args, spec, argv):
    """--quick: one sweep call per subset of the spec's "quick" list, the flags
    given on the command line kept, into one results folder."""
    subsets = spec.get("quick")
    if not subsets:
        raise SystemExit("hamal_robust_sweep: --quick: the spec has no \"quick\" subsets")
    argv = [a for a in (sys.argv[1:] if argv is None else argv) if a != "--quick"]
    status = 0
    for subset in subsets if isinstance(subsets, list) else [subsets]:
        extra = []
        for key in ("datasets", "policies", "outliers", "models", "backends", "seeds"):
            if key in subset and getattr(args, key) is None:
                extra += [f"--{key}", ",".join(str(v) for v in subset[key])]
        status = main(argv + extra) or status
    return status


def main(argv=None):
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0],
                                formatter_class=argparse.RawDescriptionHelpFormatter,
                                epilog=__doc__.split("\n\n", 1)[1])
    p.add_argument("spec")
    p.add_argument("--results", required=True)
    p.add_argument("--jobs", type=int, default=1,
                   help="runs in parallel (default 1: times are the benchmark's output)")
    p.add_argument("--bin_dir", default=None, help="where hamal_spoil and hamal_robust are "
                   "(default: build/apps)")
    p.add_argument("--quick", action="store_true",
                   help="the spec's \"quick\" subsets: one dataset, policy and seed, a few models")
    p.add_argument("--datasets", help="only these datasets of the spec (comma separated)")
    p.add_argument("--policies", help="only these policies")
    p.add_argument("--outliers", help="only these N")
    p.add_argument("--models", help="only these loop-closure models")
    p.add_argument("--backend", dest="backends", help="only the spec's runs with these back-ends")
    old_spelling(p, "--backends", "--backend")
    p.add_argument("--seeds", help="spoil with these seeds instead of the spec's "
                   "(comma separated non-negative integers)")
    p.add_argument("--timeout", type=float, default=None,
                   help="seconds a run may take before it is killed and listed as failed "
                        "(default: the spec's)")
    p.add_argument("--default_thresholds", action="store_true",
                   help="run every model at its default inlier threshold (the chi2 quantile at "
                        "0.99), not at the datasets' stated gnc_threshold; RESULTS must not hold "
                        "cells run at a stated one")
    p.add_argument("--dry_run", action="store_true")
    p.add_argument("--quiet", action="store_true")
    hamal_sweep.add_executor_arguments(p)
    args = p.parse_args(argv)
    slurm = hamal_sweep.executor_options(args)
    spec = load_spec(args.spec)
    if args.seeds is not None:
        try:
            seeds = csv_list(args.seeds, int)
        except ValueError:
            seeds = None
        if not seeds or any(seed < 0 for seed in seeds) or len(set(seeds)) != len(seeds):
            raise SystemExit(f"hamal_robust_sweep: --seeds {args.seeds!r}: expected distinct "
                             "non-negative integers, comma separated (e.g. 1,2,3)")
        spec["spoil"]["seeds"] = seeds
    if args.default_thresholds:
        for dataset in spec["datasets"].values():
            dataset.pop("gnc_threshold", None)
    if args.timeout is not None:
        spec["timeout"] = args.timeout
        for run in spec["runs"]:
            run.pop("timeout", None)
    keep = {"datasets": csv_list(args.datasets), "policies": csv_list(args.policies),
            "outliers": csv_list(args.outliers, int), "models": csv_list(args.models),
            "backends": csv_list(args.backends)}
    if args.quick:
        return quick(args, spec, argv)
    all_models = sorted({m for run in spec["runs"] for m in run_models(spec, run)})
    for key, allowed in (("datasets", spec["datasets"]), ("policies", spec["spoil"]["policies"]),
                         ("outliers", spec["spoil"]["outliers"]), ("models", all_models),
                         ("backends", [r["backend"] for r in spec["runs"]])):
        unknown = set(keep[key] or []) - set(allowed)
        if unknown:
            raise SystemExit(f"hamal_robust_sweep: no {key} {sorted(unknown)} in the spec")
    for dataset in spec["datasets"]:
        stated_threshold(spec, dataset)  # a bad one is an error before any run
    bin_dir = args.bin_dir
    spoil_bin = find_binary("hamal_spoil", bin_dir and os.path.join(bin_dir, "hamal_spoil"))
    robust_bin = find_binary("hamal_robust", bin_dir and os.path.join(bin_dir, "hamal_robust"))
    results = os.path.abspath(args.results)
    todo = cells(spec, keep)
    # One sweep per folder, from before its first write (the spoiled files,
    # robust_cells.json) to its last: a second one is refused untouched.
    lock = None if args.dry_run else resumable_results.lock(  # noqa: F841
        results, "hamal_robust_sweep: another sweep")
    # The report judges a cell's runs at the threshold robust_cells.json
    # records for it, so one folder holds one threshold per cell: checked
    # before anything is spoiled or run.
    cell_file = os.path.join(results, "robust_cells.json")
    known = {}
    if os.path.exists(cell_file):
        with open(cell_file) as f:
            known = json.load(f)
    for c in todo:
        name, stated = cell_name(*c), stated_threshold(spec, c[0])
        if name in known and known[name].get("gnc_threshold") != stated:
            raise SystemExit(f"hamal_robust_sweep: {results} holds {name} at gnc_threshold "
                             f"{known[name].get('gnc_threshold', 'default')}, this sweep would "
                             f"run it at {'the default' if stated is None else stated}: use "
                             "another results folder")
    if not args.dry_run:
        check_spoil_parameters(spec, todo, results)
    print(f"hamal_robust_sweep: {len(todo)} spoiled files", file=sys.stderr)
    spoiled = {cell_name(*c): spoil(spoil_bin, spec, c, results, args.dry_run) for c in todo}
    sub, skipped = sweep_spec(spec, spoiled, keep, os.path.dirname(robust_bin),
                              {cell_name(*c): c for c in todo})
    os.makedirs(results, exist_ok=True)
    for note in skipped:
        print(f"hamal_robust_sweep: {note['note']}", file=sys.stderr)
    atomic_json.write_json(os.path.join(results, "skipped.json"), skipped)
    # Which cell each dataset name is, for the report.
    for c in todo:
        name, stated = cell_name(*c), stated_threshold(spec, c[0])
        known[name] = {"dataset": c[0], "policy": c[1], "outliers": c[2], "seed": c[3]}
        if stated is not None:
            known[name]["gnc_threshold"] = stated
    atomic_json.write_json(cell_file, known)
    if not sub["groups"]:
        print("hamal_robust_sweep: no run left to do", file=sys.stderr)
        return 0
    return hamal_sweep.sweep(sub, results, robust_bin, max(1, args.jobs),
                             dry_run=args.dry_run, quiet=args.quiet,
                             executor=args.executor, slurm=slurm, locked=lock is not None)


if __name__ == "__main__":
    sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "common"))
    import script_errors  # noqa: E402
    sys.exit(script_errors.run("hamal_robust_sweep", main))
