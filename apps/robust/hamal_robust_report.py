#!/usr/bin/env python3
"""hamal_robust_report: the robust benchmark's tables, plots and verdicts from a
results folder of hamal_robust_sweep (apps/robust/README.md). Runs nothing.

  robust_table.csv          one row per (dataset, policy, N, model, back-end, mode),
                            the seeds of a cell summarised
  robust_report.md          one table per dataset, the verdict of every target
                            computed from the cells present ("not measured" when
                            a cell it needs is missing), runs skipped or failed
  robust_ate_<policy>.png   ATE against N for one policy, one panel per dataset,
                            the median over seeds with min-max error bars
                            (N = 0 is the clean file)

A seed is "right" when its run's status is ok (not uncertain), it rejected at most 1% of the
true loop closures, accepted at most 1% of the false edges and ends within
0.05 m ATE of the clean optimum: the Vertigo target's bar.

  hamal_robust_report.py RESULTS [--output DIR]
"""

import argparse
import csv
import json
import math
import os
import statistics
import sys

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "common"))
from old_spellings import old_spelling  # noqa: E402

try:
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
except ImportError:  # the tables and the verdicts are still written
    plt = None

MODELS = ["none", "cauchy", "huber", "dcs", "maxmix", "gnc-tls", "gnc-gm", "pcm", "pcm+gnc"]
POLICIES = ["clean", "random", "local", "random-group", "local-group"]
RIGHT_TRUE_REJECTED = 0.01   # share of the true loop closures
RIGHT_FALSE_ACCEPTED = 0.01  # share of the false edges
RIGHT_ATE = 0.05             # m
NO_HARM_ATE = 1e-3           # m
STEP_P99 = 0.010             # s
TARGET_SEEDS = 5


def spec_options(spec):
    """The key=value options of a back-end spec."""
    options = {}
    for item in spec.partition(":")[2].split(","):
        key, _, value = item.partition("=")
        if key.strip():
            options[key.strip()] = value.strip()
    return options


def model_of(spec):
    """robust=MODEL of a back-end spec ('none' without it)."""
    return spec_options(spec).get("robust") or "none"


def model_label(model, options, backend=""):
    """The model's name in the tables: gnc is gnc-tls, and a GNC or PCM model
    (or gtsam-gnc) whose chi2 threshold is not the default (gnc_threshold or
    gnc_probability, pcm_threshold or pcm_probability, gtsam-gnc's threshold
    or probability) says which, so runs at another threshold stay apart from
    the default's. pcm+gnc names PCM's apart where the two differ."""
    if model == "gnc":
        model = "gnc-tls"

    def number(key, default):
        try:
            return float(options.get(key) or default)
        except ValueError:  # pcm_threshold=auto
            return default

    def suffix(prefix):
        threshold = number(prefix + "threshold", 0)
        probability = number(prefix + "probability", 0.99)
        if threshold > 0:
            return f"c2={threshold:g}"
        if probability != 0.99:
            return f"p={probability:g}"
        return ""

    if backend == "gtsam-gnc":
        parts = [suffix("")]
    elif "pcm" in model and "gnc" in model:
        gnc, pcm = suffix("gnc_"), suffix("pcm_")
        parts = [gnc] if gnc == pcm else [gnc or "c2=default", "pcm " + (pcm or "c2=default")]
    elif "gnc" in model:
        parts = [suffix("gnc_")]
    elif "pcm" in model:
        parts = [suffix("pcm_")]
    else:
        return model
    return " ".join([model] + [p for p in parts if p])


def step_p99(path):
    """The 99th percentile of the per-step update times of an incremental run."""
    if not os.path.exists(path):
        return None
    with open(path, newline="") as f:
        times = sorted(float(r["seconds"]) for r in csv.DictReader(f)
                       if r.get("seconds") not in (None, ""))
    if not times:
        return None
    return times[min(len(times) - 1, math.ceil(0.99 * len(times)) - 1)]


def load(results):
    with open(os.path.join(results, "manifest.json")) as f:
        manifest = json.load(f)
    with open(os.path.join(results, "robust_cells.json")) as f:
        cells = json.load(f)
    runs = []
    for e in manifest["entries"]:
        if e.get("group") != "robust" or e["dataset"] not in cells:
            continue
        folder = os.path.join(results, e["dataset"], e["run_id"])
        path = os.path.join(folder, "summary.json")
        cell = cells[e["dataset"]]
        if not os.path.exists(path):
            killed = killed_run(results, e, cell)
            if killed:
                runs.append(killed)
            continue  # not run yet, or an error (listed from RESULTS/failed/)
        with open(path) as f:
            s = json.load(f)
        robust = s.get("robust") or {}
        model = model_label(robust.get("model") or model_of(e["spec"]),
                            {**spec_options(e["spec"]), **robust},
                            s.get("backend", e.get("backend")))
        true_lc = s.get("true_loop_closures") or 0
        false_n = s.get("false_edges") or 0
        run = {"dataset": cell["dataset"], "policy": cell["policy"],
               "outliers": cell["outliers"], "seed": cell["seed"], "model": model,
               "stated_threshold": cell.get("gnc_threshold"),
               "backend": s.get("backend", e.get("backend")), "mode": s.get("mode", e["mode"]),
               "status": s.get("status"), "ate": s.get("ate_translation"),
               "false_accepted": s.get("false_accepted"),
               "true_rejected": s.get("true_switched_off"),
               "precision": s.get("precision"), "recall": s.get("recall"),
               "seconds": s.get("seconds"), "gnc_iterations": s.get("gnc_iterations"),
               "true_loop_closures": true_lc, "false_edges": false_n,
               "step_p99": step_p99(os.path.join(folder, "rows.csv"))
               if s.get("mode", e["mode"]) == "incremental" else None}
        run["right"] = right(run)
        # Below the clean map on the TLS objective: no exact solver of that
        # objective would return the clean map (the model's failure).
        tls, clean = s.get("tls_objective"), s.get("tls_objective_clean")
        run["tls_below_clean"] = (tls is not None and clean is not None
                                  and tls < clean - 1e-9 * abs(clean))
        runs.append(run)
    return runs


def killed_run(results, e, cell):
    """A run killed at the sweep's timeout is a result: the model did not finish
    in time. (A run that ended in an error, e.g. a model the binary does not
    know, is not measured and only listed.)"""
    path = os.path.join(results, "failed", e["dataset"], e["run_id"], "config.json")
    if not os.path.exists(path):
        return None
    with open(path) as f:
        c = json.load(f)
    if c.get("exit_status", 0) >= 0:
        return None
    model = model_label(model_of(e["spec"]), spec_options(e["spec"]), e.get("backend"))
    run = {"dataset": cell["dataset"], "policy": cell["policy"], "outliers": cell["outliers"],
           "seed": cell["seed"], "model": model, "stated_threshold": cell.get("gnc_threshold"),
           "backend": c.get("backend", e.get("backend")), "mode": c.get("mode", e["mode"]),
           "status": f"killed after {c.get('wall_seconds', 0):.0f} s", "right": False}
    for k in ("ate", "false_accepted", "true_rejected", "precision", "recall", "seconds",
              "gnc_iterations", "step_p99"):
        run[k] = None
    run["true_loop_closures"] = run["false_edges"] = 0
    return run


def right(r):
    if r["status"] != "ok" or r["ate"] is None or r["true_rejected"] is None \
            or r["false_accepted"] is None:
        return False
    true_share = r["true_rejected"] / r["true_loop_closures"] if r["true_loop_closures"] else 0
    false_share = r["false_accepted"] / r["false_edges"] if r["false_edges"] else 0
    return (true_share <= RIGHT_TRUE_REJECTED and false_share <= RIGHT_FALSE_ACCEPTED
            and r["ate"] <= RIGHT_ATE)


def finite(values):
    return [v for v in values if v is not None and isinstance(v, (int, float)) and
            math.isfinite(v)]


def median(values):
    xs = finite(values)
    return statistics.median(xs) if xs else None


def method_key(r):
    return (r["model"], r["backend"], r["mode"])


def method_order(m):
    model, backend, mode = m
    base = model.split(" ")[0]  # a threshold study's rows follow their model's
    return (MODELS.index(base) if base in MODELS else len(MODELS), mode, backend, model)


def aggregate(runs):
    """One row per cell and method, the seeds summarised."""
    groups = {}
    for r in runs:
        groups.setdefault((r["dataset"], r["policy"], r["outliers"]) + method_key(r), []).append(r)
    rows = []
    for key, rs in groups.items():
        row = dict(zip(["dataset", "policy", "outliers", "model", "backend", "mode"], key))
        ates = finite([r["ate"] for r in rs])
        row.update({
            "seeds": len(rs), "seed_list": sorted(r["seed"] for r in rs),
            "status": ",".join(sorted({str(r["status"]) for r in rs})),
            "ate_median": median(ates), "ate_min": min(ates) if ates else None,
            "ate_max": max(ates) if ates else None,
            "false_accepted": median([r["false_accepted"] for r in rs]),
            "false_accepted_max": max(finite([r["false_accepted"] for r in rs]), default=None),
            "true_rejected": median([r["true_rejected"] for r in rs]),
            "true_rejected_max": max(finite([r["true_rejected"] for r in rs]), default=None),
            "precision": median([r["precision"] for r in rs]),
            "recall": median([r["recall"] for r in rs]),
            "seconds": median([r["seconds"] for r in rs]),
            "step_p99": median([r["step_p99"] for r in rs]),
            "right": sum(r["right"] for r in rs) / len(rs)})
        rows.append(row)
    rows.sort(key=lambda r: (r["dataset"], POLICIES.index(r["policy"])
                             if r["policy"] in POLICIES else 99, r["outliers"],
                             method_order(method_key(r))))
    return rows


def fmt(x, digits=3, pct=False):
    if x is None:
        return "-"
    if pct:
        return f"{100 * x:.1f}%"
    if x != 0 and (abs(x) < 1e-3 or abs(x) >= 1e5):
        return f"{x:.{digits - 1}e}"
    return f"{x:.{digits}g}"


def method_label(m):
    model, backend, mode = m
    return f"{model}, {backend} ({mode})"


CSV_KEYS = ["dataset", "policy", "outliers", "model", "backend", "mode", "seeds", "status",
            "ate_median", "ate_min", "ate_max", "false_accepted", "false_accepted_max",
            "true_rejected", "true_rejected_max", "precision", "recall", "seconds", "step_p99",
            "right"]


def write_csv(rows, path):
    with open(path, "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=CSV_KEYS, extrasaction="ignore")
        w.writeheader()
        for r in rows:
            w.writerow({k: ("" if r.get(k) is None else r[k]) for k in CSV_KEYS})


def dataset_table(rows, dataset):
    md = [f"### {dataset}", "",
          "| policy | N | model | back-end (mode) | seeds | ATE median (min-max) m | false "
          "accepted | true rejected | precision | recall | time (s) | step p99 (ms) | right | "
          "status |", "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|"]
    for r in rows:
        if r["dataset"] != dataset:
            continue
        ate = fmt(r["ate_median"])
        if r["seeds"] > 1 and r["ate_min"] is not None:
            ate += f" ({fmt(r['ate_min'])}-{fmt(r['ate_max'])})"
        md.append(
            f"| {r['policy']} | {r['outliers']} | {r['model']} | {r['backend']} ({r['mode']}) | "
            f"{r['seeds']} | {ate} | {fmt(r['false_accepted'])} | {fmt(r['true_rejected'])} | "
            f"{fmt(r['precision'], pct=True)} | {fmt(r['recall'], pct=True)} | "
            f"{fmt(r['seconds'])} | "
            f"{fmt(r['step_p99'] * 1e3 if r['step_p99'] is not None else None)} | "
            f"{fmt(r['right'], pct=True)} | {r['status']} |")
    return md + [""]


# ---------------------------------------------------------------------------
# The targets: each verdict is computed from the runs present.

def judged(r, model):
    """A run of `model` at its dataset's stated inlier threshold (the default
    where the spec states none): the runs the targets judge."""
    t = r.get("stated_threshold") or 0
    stated = {"gnc_threshold": t, "pcm_threshold": t, "threshold": t}
    return r["model"] == model_label(model, stated, r["backend"])


def is_batch_gnc(r):
    return judged(r, "gnc-tls") and r["mode"] == "batch" and r["backend"] != "gtsam-gnc"


def is_incremental_gnc(r):
    return judged(r, "gnc-tls") and r["mode"] == "incremental"


def is_pcm_gnc(r):
    return judged(r, "pcm+gnc")


def verdict(name, checked, missing):
    """checked: (label, holds, detail) of every measured case; missing: labels not measured."""
    missing = list(dict.fromkeys(missing))  # each once, in order
    failing = [c for c in checked if not c[1]]
    if failing:
        head = f"FAILS on {len(failing)} of {len(checked)} measured cases"
    elif not checked:
        head = "not measured"
    elif missing:
        head = f"not measured in full (holds on the {len(checked)} measured cases)"
    else:
        head = f"holds on all {len(checked)} cases"
    line = f"- **{name}: {head}.**"
    if failing:
        line += " Failing: " + "; ".join(f"{c[0]} ({c[2]})" for c in failing[:20])
        line += " ..." if len(failing) > 20 else "."
    if missing:
        line += " Not measured: " + "; ".join(missing[:20]) + (" ..." if len(missing) > 20 else ".")
    return line


def model_note(r):
    return "; TLS objective below the clean map's" if r.get("tls_below_clean") else ""


def run_label(r):
    return (f"{method_label(method_key(r))}, {r['dataset']} {r['policy']} N={r['outliers']}"
            + (f" s{r['seed']}" if r["outliers"] else ""))


def no_harm(runs, datasets):
    checked, missing = [], []
    for ds in datasets:
        for what, pick in (("batch gnc-tls", is_batch_gnc), ("incremental gnc", is_incremental_gnc),
                           ("pcm+gnc", is_pcm_gnc)):
            rs = [r for r in runs if r["dataset"] == ds and r["outliers"] == 0 and pick(r)]
            if not rs:
                missing.append(f"{what} on {ds}")
            for r in rs:
                ok = (r["status"] == "ok" and r["true_rejected"] == 0 and r["ate"] is not None
                      and r["ate"] <= NO_HARM_ATE)
                # The same back-end's least squares says how much of the ATE is the back-end's.
                plain = [p for p in runs if p["dataset"] == ds and p["outliers"] == 0 and
                         (p["model"], p["backend"], p["mode"]) == ("none", r["backend"], r["mode"])]
                context = f"; least squares there {fmt(plain[0]['ate'])} m" if plain else ""
                checked.append((run_label(r), ok, f"{fmt(r['true_rejected'])} true rejected, "
                                f"ATE {fmt(r['ate'])} m, {r['status']}{context}{model_note(r)}"))
    return verdict(f"No harm (N = 0: no true closure rejected, ATE <= {NO_HARM_ATE:g} m)",
                   checked, missing)


def seed_cases(runs, datasets, policies, n, picks):
    """Every (method class, dataset, policy) needs TARGET_SEEDS seeds."""
    checked, missing = [], []
    for ds in datasets:
        for policy in policies:
            for what, pick in picks:
                rs = [r for r in runs if (r["dataset"], r["policy"], r["outliers"]) ==
                      (ds, policy, n) and pick(r)]
                for m in sorted({method_key(r) for r in rs}, key=method_order):
                    seeds = {r["seed"] for r in rs if method_key(r) == m}
                    if len(seeds) < TARGET_SEEDS:
                        missing.append(f"{method_label(m)} {ds} {policy}: "
                                       f"{len(seeds)} of {TARGET_SEEDS} seeds")
                if not rs:
                    missing.append(f"{what} on {ds} {policy} N={n}")
                checked += [(r, None, None) for r in rs]
    return checked, missing


def vertigo(runs):
    cases, missing = seed_cases(runs, ["M3500", "city10000"], ["random", "random-group"], 1000,
                                [("batch gnc-tls", is_batch_gnc),
                                 ("incremental gnc", is_incremental_gnc)])
    checked = [(run_label(r), r["right"],
                f"{fmt(r['true_rejected'])} true rejected, {fmt(r['false_accepted'])} false "
                f"accepted, ATE {fmt(r['ate'])} m, {r['status']}{model_note(r)}")
               for r, _, _ in cases]
    return verdict("Vertigo N = 1000, random and random-group, M3500 and city10000, every seed "
                   "(true rejected <= 1%, false accepted <= 1%, ATE <= 0.05 m)", checked, missing)


def seeds_right_line(runs):
    """Intel and the local policies are reported, not bound: the share of seeds right."""
    parts = []
    for ds, policy in [("intel", "random"), ("intel", "random-group")] + [
            (d, p) for d in ("M3500", "city10000", "intel", "manhattan", "CSAIL")
            for p in ("local", "local-group")]:
        rs = [r for r in runs if (r["dataset"], r["policy"], r["outliers"]) == (ds, policy, 1000)]
        if not rs:
            continue
        by = {}
        for r in rs:
            by.setdefault(method_key(r), []).append(r["right"])
        best = sorted(by.items(), key=lambda kv: (-sum(kv[1]) / len(kv[1]), method_order(kv[0])))
        parts.append(f"{ds} {policy}: " + ", ".join(
            f"{method_label(m)} {sum(v)}/{len(v)}" for m, v in best[:3]))
    if not parts:
        return "- **Intel and the local policies at N = 1000 (reported): not measured.**"
    return ("- **Intel and the local policies at N = 1000 (reported; seeds right, best three "
            "methods):** " + "; ".join(parts) + ".")


def cost(runs):
    checked, missing = [], []
    # Incremental gnc on M3500 + 1000 random against the same back-end's plain clean run.
    inc = [r for r in runs if is_incremental_gnc(r) and (r["dataset"], r["policy"],
                                                        r["outliers"]) == ("M3500", "random", 1000)]
    if not inc:
        missing.append("incremental gnc on M3500 random N=1000")
    for r in inc:
        clean = [c for c in runs if (c["dataset"], c["outliers"], c["model"], c["backend"],
                                     c["mode"]) == ("M3500", 0, "none", r["backend"], r["mode"])]
        if not clean:
            missing.append(f"{r['backend']} robust=none on clean M3500 (the time to compare with)")
            continue
        base = clean[0]["seconds"]
        x = r["seconds"] / base if base and r["seconds"] is not None else None
        ok = x is not None and x <= 3 and r["step_p99"] is not None and r["step_p99"] < STEP_P99
        checked.append((run_label(r), ok, f"{fmt(x)}x the clean run's {fmt(base)} s, step p99 "
                        f"{fmt(r['step_p99'] * 1e3 if r['step_p99'] is not None else None)} ms, "
                        f"{r['status']}"))
    # Batch gnc-tls on city10000 + 1000 against gtsam-gnc on the same spoiled file.
    bat = [r for r in runs if is_batch_gnc(r) and r["dataset"] == "city10000"
           and r["outliers"] == 1000 and r["policy"] == "random"]
    gtsam = {(r["policy"], r["seed"]): r for r in runs if r["backend"] == "gtsam-gnc"
             and judged(r, "none") and r["dataset"] == "city10000" and r["outliers"] == 1000}
    if not bat:
        missing.append("batch gnc-tls on city10000 random N=1000")
    for r in bat:
        g = gtsam.get((r["policy"], r["seed"]))
        if not g:
            missing.append(f"gtsam-gnc on city10000 {r['policy']} N=1000 s{r['seed']}")
            continue
        x = (r["seconds"] / g["seconds"] if g["seconds"] and r["seconds"] is not None
             else None)
        ok = (x is not None and x <= 0.5 and r["ate"] is not None and g["ate"] is not None and r["ate"] <= g["ate"])
        checked.append((run_label(r), ok, f"{fmt(x)}x gtsam-gnc's {fmt(g['seconds'])} s, ATE "
                        f"{fmt(r['ate'])} m vs {fmt(g['ate'])} m"))
    return verdict("Cost (incremental gnc on M3500 + 1000 random: <= 3x the plain clean run, "
                   "step p99 < 10 ms; batch gnc-tls on city10000 + 1000: <= 0.5x gtsam-gnc's "
                   "time, ATE no worse)", checked, missing)


def beyond_maxmix(runs):
    checked, missing = [], []
    cases = [("manhattan", "clean", 0, 0), ("M3500", "random", 1000, 2), ("M3500", "random", 1000, 4)]
    for ds, policy, n, seed in cases:
        for what, pick in (("batch gnc-tls", is_batch_gnc), ("incremental gnc", is_incremental_gnc)):
            rs = [r for r in runs if (r["dataset"], r["policy"], r["outliers"], r["seed"]) ==
                  (ds, policy, n, seed) and pick(r)]
            if not rs:
                missing.append(f"{what} on {ds} {policy} N={n}" + (f" s{seed}" if n else ""))
            for r in rs:
                ok = r["right"] and (n > 0 or r["true_rejected"] == 0)
                checked.append((run_label(r), ok, f"{fmt(r['true_rejected'])} true rejected, "
                                f"ATE {fmt(r['ate'])} m, {r['status']}"))
    return verdict("Better than max-mixtures where they fail (manhattan N = 0 with no true "
                   "closure rejected; M3500 random 1000 seeds 2 and 4 right)", checked, missing)


def targets(runs):
    datasets = ["M3500", "intel", "city10000", "manhattan", "CSAIL"]
    return [no_harm(runs, datasets), vertigo(runs), seeds_right_line(runs), cost(runs),
            beyond_maxmix(runs)]


# ---------------------------------------------------------------------------
# Figures and the lists of runs without a result.

def plot(rows, out):
    """One figure per policy: ATE against N, a panel per dataset, error bars min-max."""
    if plt is None:
        return []
    images = []
    policies = [p for p in POLICIES if p != "clean" and any(
        r["policy"] == p for r in rows)]
    for policy in policies:
        datasets = sorted({r["dataset"] for r in rows if r["policy"] == policy})
        cols = min(3, len(datasets))
        nrows = (len(datasets) + cols - 1) // cols
        fig, axes = plt.subplots(nrows, cols, figsize=(4.6 * cols, 3.6 * nrows), squeeze=False)
        for ax, ds in zip(axes.flat, datasets):
            here = [r for r in rows if r["dataset"] == ds and r["ate_median"] is not None
                    and (r["policy"] == policy or r["outliers"] == 0)]
            for i, m in enumerate(sorted({method_key(r) for r in here}, key=method_order)):
                pts = sorted((r["outliers"], r["ate_median"], r["ate_min"], r["ate_max"])
                             for r in here if method_key(r) == m)
                xs = [max(p[0], 1) for p in pts]  # N = 0 drawn at 1 on the log axis
                ys = [max(p[1], 1e-9) for p in pts]
                err = [[max(p[1] - p[2], 0) for p in pts], [max(p[3] - p[1], 0) for p in pts]]
                ax.errorbar(xs, ys, yerr=err, color=f"C{i % 10}",
                            linestyle=["-", "--", ":", "-."][i // 10 % 4], marker="o", ms=3,
                            capsize=2, label=method_label(m))
            ax.set_xscale("log")
            ax.set_yscale("log")
            ax.set_title(f"{ds}, {policy}", fontsize=9)
            ax.set_xlabel("false loop closures N (N = 0 drawn at 1)", fontsize=8)
            ax.set_ylabel("ATE vs clean optimum (m), median, min-max", fontsize=8)
            ax.grid(True, which="both", alpha=0.3)
            ax.legend(fontsize=6)
        for ax in list(axes.flat)[len(datasets):]:
            ax.axis("off")
        fig.tight_layout()
        name = f"robust_ate_{policy}.png"
        fig.savefig(os.path.join(out, name), dpi=110)
        plt.close(fig)
        images.append(name)
    return images


def failed_runs(results):
    """Runs the sweep runner moved to RESULTS/failed (an error, or over the timeout)."""
    out = []
    base = os.path.join(results, "failed")
    if not os.path.isdir(base):
        return out
    for dname in sorted(os.listdir(base)):
        for rid in sorted(os.listdir(os.path.join(base, dname))):
            path = os.path.join(base, dname, rid, "config.json")
            if not os.path.exists(path) or os.path.isdir(os.path.join(results, dname, rid)):
                continue  # no config, or redone since and finished
            with open(path) as f:
                c = json.load(f)
            reason = ""
            log = os.path.join(base, dname, rid, "log.txt")
            if c.get("exit_status", 0) < 0:
                reason = ": killed at the sweep's timeout"
            elif os.path.exists(log):
                with open(log, errors="replace") as f:
                    lines = [ln.strip() for ln in f if ln.strip()]
                reason = f": {lines[-1][:200]}" if lines else ""
            out.append(f"- {dname}: `{c['spec']}` ({c['mode']}): exit {c['exit_status']} after "
                       f"{c['wall_seconds']:.0f} s{reason}")
    return out


def skipped_runs(results):
    path = os.path.join(results, "skipped.json")
    if not os.path.exists(path):
        return []
    with open(path) as f:
        return [f"- {s['note']}" for s in json.load(f)]


def report(results, out):
    runs = load(results)
    rows = aggregate(runs)
    os.makedirs(out, exist_ok=True)
    write_csv(rows, os.path.join(out, "robust_table.csv"))
    images = plot(rows, out)
    md = ["# Robust pose-graph benchmark", "",
          f"{len(runs)} runs from `{results}` (apps/robust/README.md says what each column is). "
          "ATE: translation RMSE after rigid alignment against the clean file's least-squares "
          "batch optimum, median over seeds (min-max); false accepted, true rejected: medians "
          "over seeds of the false edges the model kept and the true loop closures it rejected; "
          "precision: rejected edges that are false; recall: false edges rejected; time: the "
          "update calls (s, median); step p99: the 99th percentile of an incremental run's step "
          f"times; right: the share of seeds with status ok, <= {RIGHT_TRUE_REJECTED:.0%} true "
          f"rejected, <= {RIGHT_FALSE_ACCEPTED:.0%} false accepted and ATE <= {RIGHT_ATE:g} m.",
          "", "## Targets", ""] + targets(runs) + [""]
    for name in images:
        md += [f"![ATE against N, {name[len('robust_ate_'):-4]}]({name})", ""]
    notes = skipped_runs(results)
    if notes:
        md += ["## Runs skipped", ""] + notes + [""]
    failed = failed_runs(results)
    if failed:
        md += ["## Runs without a result (error or timeout: a negative exit status is a kill)",
               ""] + failed + [""]
    md += ["## Tables", ""]
    for ds in sorted({r["dataset"] for r in rows}):
        md += dataset_table(rows, ds)
    with open(os.path.join(out, "robust_report.md"), "w") as f:
        f.write("\n".join(md) + "\n")
    return rows


def main(argv=None):
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0],
                                formatter_class=argparse.RawDescriptionHelpFormatter,
                                epilog=__doc__.split("\n\n", 1)[1])
    p.add_argument("results")
    p.add_argument("--output", dest="out", default=None, help="default: RESULTS/report")
    old_spelling(p, "--out", "--output")
    args = p.parse_args(argv)
    out = args.out or os.path.join(args.results, "report")
    rows = report(os.path.abspath(args.results), out)
    print(f"hamal_robust_report: {len(rows)} rows -> {out}/robust_report.md", file=sys.stderr)
    return 0


if __name__ == "__main__":
    sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "common"))
    import script_errors  # noqa: E402
    sys.exit(script_errors.run("hamal_robust_report", main))
