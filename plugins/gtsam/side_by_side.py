#!/usr/bin/env python3
"""side_by_side: the tables and the scale plot of AprilSAM against GTSAM's
iSAM2 (thesis sec. 3.5, tables 3.2-3.4 and the scale study), from the
hamal_bench runs scripts/isam2.sh leaves in RESULTS:

  RESULTS/<dataset>/summary.csv   hamal_bench --summary (medians of --repeat runs)
  RESULTS/<dataset>/rows.csv      hamal_bench --rows (every step of every run)
  RESULTS/<dataset>/machine.txt   the command, load before and after, revision

and writes

  RESULTS/side_by_side.csv   one row per dataset and back-end
  RESULTS/side_by_side.md    the markdown table (with the machine and load)
  RESULTS/scale.png/.svg     cumulative time against poses on the generated
                             worlds, log-log, one line per back-end and world,
                             with the fitted slopes in the legend

A back-end stopped by a time budget (scripts/isam2.sh BUDGET, hamal_bench
--time_budget) shows the steps it reached; the ratio is then taken at the
poses both back-ends reached ("at n poses: r"), and the stopped curve is
plotted but left out of the slope across worlds.

Times are hamal_bench's: only update() is timed; "step" is the whole update
(for iSAM2 that includes calculateEstimate, which the protocol needs every
step), "update only" leaves out PhaseTimes::estimate. chi2 is hamal's one
evaluator on each back-end's estimate; the objective (thesis or
measurement-frame between residual) is the one the runs were made with
(machine.txt), and every back-end, GTSAM's included, minimised that one.

  side_by_side.py RESULTS
"""

import csv
import math
import os
import sys


def read_summary(path):
    with open(path) as f:
        return list(csv.DictReader(f))


def read_machine(path):
    info = {}
    if os.path.exists(path):
        with open(path) as f:
            for line in f:
                if ":" in line:
                    k, v = line.split(":", 1)
                    info[k.strip()] = v.strip()
    return info


def cumulative_curves(rows_path):
    """backend -> list of (poses, cumulative seconds): the median over the
    runs of each step's time, accumulated. A back-end that computes its
    estimate apart (estimate_seconds > 0: iSAM2) gets a second series,
    "<backend> update only", without it."""
    with open(rows_path) as f:
        rows = list(csv.DictReader(f))
    apart = {r["backend"] for r in rows if float(r.get("estimate_seconds") or 0) > 0}
    per = {}
    for r in rows:
        seconds = float(r["seconds"])
        per.setdefault(r["backend"], {}).setdefault(int(r["step"]), []).append(seconds)
        if r["backend"] in apart:
            per.setdefault(r["backend"] + UPDATE_ONLY, {}).setdefault(int(r["step"]), []).append(
                seconds - float(r.get("estimate_seconds") or 0))
    curves = {}
    for backend, steps in per.items():
        total, curve = 0.0, []
        for step in sorted(steps):
            times = sorted(steps[step])
            n = len(times)
            median = times[n // 2] if n % 2 else 0.5 * (times[n // 2 - 1] + times[n // 2])
            total += median
            curve.append((step + 1, total))
        curves[backend] = curve
    return curves


UPDATE_ONLY = " update only"


def base_backend(series):
    """The back-end a curve of cumulative_curves belongs to."""
    return series[:-len(UPDATE_ONLY)] if series.endswith(UPDATE_ONLY) else series


def loglog_slope(points):
    """Least-squares slope of log(y) against log(x); None with < 2 points."""
    pts = [(math.log(x), math.log(y)) for x, y in points if x > 0 and y > 0]
    if len(pts) < 2:
        return None
    mx = sum(p[0] for p in pts) / len(pts)
    my = sum(p[1] for p in pts) / len(pts)
    sxx = sum((p[0] - mx) ** 2 for p in pts)
    if sxx == 0:
        return None
    return sum((p[0] - mx) * (p[1] - my) for p in pts) / sxx


def fmt(v, digits=3):
    try:
        v = float(v)
    except (TypeError, ValueError):
        return "-"
    if math.isnan(v):
        return "-"
    return f"{v:.{digits}f}"


def is_isam2(backend):
    return backend == "isam2" or backend.startswith("isam2:")


def main(argv):
    if len(argv) != 2:
        sys.exit(__doc__)
    results = argv[1]
    datasets = sorted(d for d in os.listdir(results)
                      if os.path.exists(os.path.join(results, d, "summary.csv")))
    if not datasets:
        sys.exit(f"side_by_side: no finished dataset in {results}")
    rows, machines = [], {}
    for d in datasets:
        machines[d] = read_machine(os.path.join(results, d, "machine.txt"))
        for s in read_summary(os.path.join(results, d, "summary.csv")):
            s["name"] = d
            rows.append(s)

    def stopped(r):
        return r.get("stopped_by_budget", "0") in ("1", "true")
    stopped_runs = {(r["name"], r["backend"]) for r in rows if stopped(r)}
    curves_of = {}  # dataset -> cumulative_curves of its rows, read once

    def curves_for(d):
        if d not in curves_of:
            curves_of[d] = cumulative_curves(os.path.join(results, d, "rows.csv"))
        return curves_of[d]

    # Each AprilSAM back-end's time over iSAM2's (default options), per dataset.
    ratios = {}
    for d in datasets:
        by = {r["backend"]: r for r in rows if r["name"] == d}
        if "isam2" not in by:
            continue
        for b in by:
            if not b.startswith("aprilsam"):
                continue
            a = float(by[b]["cumulative_seconds"])
            if stopped(by["isam2"]) or stopped(by[b]):
                # Compared at the poses both reached: cumulative times there.
                curves = curves_for(d)
                n = min(len(curves[b]), len(curves["isam2"]))
                a = curves[b][n - 1][1]
                ratios[d, b] = (a / curves["isam2" + UPDATE_ONLY][n - 1][1],
                                a / curves["isam2"][n - 1][1], f"at {n} poses: ")
            else:
                ratios[d, b] = (a / float(by["isam2"]["update_only_seconds"]),
                                a / float(by["isam2"]["cumulative_seconds"]), "")

    out_csv = os.path.join(results, "side_by_side.csv")
    fields = ["dataset", "backend", "steps", "repeats", "cumulative_seconds", "update_only_seconds",
              "p99_seconds", "final_chi2", "optimum_chi2", "chi2_ratio", "non_ok_steps",
              "residual", "load_before", "load_after"]
    with open(out_csv, "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=fields)
        w.writeheader()
        for r in rows:
            m = machines[r["name"]]
            w.writerow({"dataset": r["name"], "backend": r["backend"], "steps": r["steps"],
                        "repeats": r["repeats"], "cumulative_seconds": r["cumulative_seconds"],
                        "update_only_seconds": r["update_only_seconds"],
                        "p99_seconds": r["p99_seconds"], "final_chi2": r["final_chi2"],
                        "optimum_chi2": r["optimum_chi2"], "chi2_ratio": r["chi2_ratio"],
                        "non_ok_steps": r["non_ok_steps"], "residual": m.get("residual", ""),
                        "load_before": m.get("load before", ""),
                        "load_after": m.get("load after", "")})

    lines = ["| dataset | back-end | step time s (median of runs) | update only s | p99 ms | "
             "final chi2 | chi2/opt | aprilsam / iSAM2 (update only; step) |",
             "|---|---|---|---|---|---|---|---|"]
    for r in rows:
        ratio = ""
        if (r["name"], r["backend"]) in ratios:
            u, c, where = ratios[r["name"], r["backend"]]
            ratio = f"{where}{u:.2f}; {c:.2f}"
        lines.append(
            f"| {r['name']}{' (stopped at step ' + r['steps'] + ')' if stopped(r) else ''} | "
            f"`{r['backend']}` | {fmt(r['cumulative_seconds'])} | "
            f"{fmt(r['update_only_seconds'])} | {fmt(float(r['p99_seconds']) * 1e3, 2)} | "
            f"{fmt(r['final_chi2'], 4)} | {fmt(r['chi2_ratio'], 6)} | {ratio} |")
    lines.append("")
    for d in datasets:
        m = machines[d]
        lines.append(f"- {d}: {m.get('residual', '?')} residual, {m.get('repeats', '?')} runs, "
                     f"load before {m.get('load before', '?')}, after {m.get('load after', '?')}; "
                     f"{m.get('machine', '')}")

    # The scale study: generated worlds only (their names start with "gen").
    worlds = [d for d in datasets if d.startswith("gen")]
    slopes = []
    plotted = False
    if worlds:
        curves = {d: curves_for(d) for d in worlds}
        backends = sorted({b for d in worlds for b in curves[d]})
        lines.append("")
        lines.append("Scale (generated worlds): cumulative step time against poses, "
                     "log-log slopes fitted")
        lines.append("")
        lines.append("| back-end | worlds | slope over the worlds' final times | "
                     "slope of the largest world's curve, last decade |")
        lines.append("|---|---|---|---|")
        for b in backends:
            finals = [curves[d][b][-1] for d in worlds
                      if b in curves[d] and (d, base_backend(b)) not in stopped_runs]
            across = loglog_slope(finals)
            largest = max((d for d in worlds if b in curves[d]), key=lambda d: len(curves[d][b]))
            curve = curves[largest][b]
            n = len(curve)
            tail = [p for p in curve if p[0] >= n / 10]
            step = max(1, len(tail) // 200)
            within = loglog_slope(tail[::step])
            slopes.append((b, across, within))
            lines.append(f"| `{b}` | {', '.join(str(p[0]) for p in finals)} | "
                         f"{fmt(across, 2)} | {fmt(within, 2)} ({largest}) |")
        try:
            import matplotlib
            matplotlib.use("Agg")
            import matplotlib.pyplot as plt
        except ImportError:
            print("side_by_side: no matplotlib (apt-get install python3-matplotlib): no plot")
        else:
            fig, ax = plt.subplots(figsize=(7, 5))
            colors = {}
            for b, across, within in slopes:
                label_done = False
                for d in worlds:
                    if b not in curves[d]:
                        continue
                    xs = [p[0] for p in curves[d][b]]
                    ys = [p[1] for p in curves[d][b]]
                    label = None
                    if not label_done:
                        label = f"{b} (slope {fmt(across, 2)} across worlds, " \
                                f"{fmt(within, 2)} within)"
                        label_done = True
                    base = base_backend(b)
                    line, = ax.loglog(xs, ys, color=colors.get(base), label=label, linewidth=1,
                                      linestyle="--" if base != b else "-")
                    colors[base] = line.get_color()
            ax.set_xlabel("poses")
            ax.set_ylabel("cumulative step time [s] (median of runs)")
            ax.set_title("AprilSAM and iSAM2 on generated Manhattan worlds")
            ax.grid(True, which="both", alpha=0.3)
            ax.legend(fontsize=8)
            fig.tight_layout()
            for ext in ("png", "svg"):
                fig.savefig(os.path.join(results, f"scale.{ext}"))
            plotted = True
            lines.append("")
            lines.append("![scale](scale.png)")

    out_md = os.path.join(results, "side_by_side.md")
    with open(out_md, "w") as f:
        f.write("\n".join(lines) + "\n")
    print("\n".join(lines))
    print(f"\nwrote {out_csv}, {out_md}" + (", scale.png/.svg" if plotted else ""))


if __name__ == "__main__":
    main(sys.argv)
