#!/usr/bin/env python3
"""moss_report: the figures of thesis sec. 5.5 from a hamal_moss experiment
folder (rows.csv, map.csv, walls.csv, test_trials.csv):

  rmse.png / rmse.svg    test RMSE against C per method, error bars of 3
                         standard errors over the test trials, the full map
                         as a dashed line (figs. 5.6 and 5.9)
  nodes.png / nodes.svg  the nodes each method selects on the world, for a
                         few C (figs. 5.7 and 5.10)
  table.md               every row, and the thesis' claims with whether each
                         holds here; with per-trial errors in the rows (new
                         folders), the verdicts come from paired tests over
                         the test trials (below), not from means
  summary.md             one table row: no map, full map and MOSS at the C
                         its training error picks, each as the median of the
                         per-trial test RMSEs with a 95% bootstrap interval,
                         and the paired tests' p values

Paired test: the one-sided Wilcoxon signed-rank test (scipy) on the per-trial
test RMSE differences, "A better than B" holding when p < 0.05; without scipy
the exact sign test. MOSS's C is the one its training error picks (ties: the
smaller C), never the test error.

  moss_report.py DIR [--nodes_sizes 1,2,3,4]
"""

import argparse
import csv
import os
import sys

METHODS = ["equidistant", "ssm", "moss"]
LABELS = {"equidistant": "Equidistant", "ssm": "SSM", "moss": "MOSS", "full": "full map",
          "none": "no map"}
COLORS = {"equidistant": "tab:blue", "ssm": "tab:orange", "moss": "tab:green"}


def read_rows(folder):
    with open(os.path.join(folder, "rows.csv")) as f:
        rows = list(csv.DictReader(f))
    for r in rows:
        r["C"] = int(r["C"])
        for k in ("train_rmse", "test_rmse", "test_rmse_se", "seconds", "ms_per_evaluation"):
            r[k] = float(r[k])
        # Eq. 5.3's error (mean norm), in folders that have it.
        for k in ("test_mean_error", "test_mean_error_se"):
            r[k] = float(r[k]) if r.get(k) not in (None, "") else float("nan")
        r["nodes"] = [int(x) for x in r["nodes"].split()] if r["nodes"] else []
        # Per test trial RMSE, in folders that have it (paired tests).
        t = r.get("test_trial_rmse")
        r["trials"] = [float(x) for x in t.split()] if t else []
    return rows


ALPHA = 0.05


def paired_p(a, b):
    """One-sided p that a's errors are lower than b's (paired by trial), and the test's name."""
    d = [x - y for x, y in zip(a, b)]
    if all(x == 0 for x in d):
        return 1.0, "no difference"
    try:
        from scipy.stats import wilcoxon
        return float(wilcoxon(a, b, alternative="less").pvalue), "Wilcoxon signed-rank"
    except ImportError:
        # Exact sign test: P(at most k of n nonzero differences positive).
        from math import comb
        nz = [x for x in d if x != 0]
        n, k = len(nz), sum(1 for x in nz if x > 0)
        return sum(comb(n, i) for i in range(k + 1)) / 2.0 ** n, "sign test"


def median(v):
    v = sorted(v)
    n = len(v)
    return (v[(n - 1) // 2] + v[n // 2]) / 2.0


def bootstrap_ci(v, resamples=2000, seed=1):
    """95% percentile bootstrap interval of the median."""
    import random
    rng = random.Random(seed)
    meds = sorted(median([rng.choice(v) for _ in v]) for _ in range(resamples))
    return meds[int(0.025 * resamples)], meds[int(0.975 * resamples) - 1]


def training_choice(rows):
    """MOSS's row at the C its training error picks (ties: the smaller C)."""
    moss = [r for r in rows if r["method"] == "moss"]
    return min(moss, key=lambda r: (r["train_rmse"], r["C"])) if moss else None


def paired_claims(rows):
    """Verdicts from paired tests over the test trials (folders with per-trial errors)."""
    by = {r["method"]: r for r in rows if r["method"] in ("none", "full")}
    moss = training_choice(rows)
    arms = [(k, by[k]) for k in ("none", "full") if k in by]
    if moss:
        arms.append(("moss", moss))
    out = []

    def name(k, r):
        return "MOSS (C = %d, by training)" % r["C"] if k == "moss" else LABELS[k]

    for (ka, a), (kb, b) in [(x, y) for x in arms for y in arms
                             if (x[0], y[0]) in (("moss", "none"), ("full", "none"),
                                                 ("moss", "full"))]:
        p, test = paired_p(a["trials"], b["trials"])
        d = [x - y for x, y in zip(a["trials"], b["trials"])]
        out.append("%s better than %s: p = %.3g (%s, n = %d trials, median difference %+.3f m): "
                   "%s" % (name(ka, a), name(kb, b).replace("full map", "the full map"), p,
                           test, len(d), median(d), "holds" if p < ALPHA else "does not hold"))
    if moss:
        for k in ("equidistant", "ssm"):
            o = [r for r in rows if r["method"] == k and r["C"] == moss["C"]]
            if o and o[0]["trials"]:
                p, test = paired_p(moss["trials"], o[0]["trials"])
                out.append("MOSS better than %s at C = %d: p = %.3g (%s): %s" % (
                    LABELS[k], moss["C"], p, test, "holds" if p < ALPHA else "does not hold"))
    return out


def summary_row(rows):
    """no map, full map, MOSS at the training C: median [95% CI] of the per-trial test RMSE."""
    by = {r["method"]: r for r in rows if r["method"] in ("none", "full")}
    moss = training_choice(rows)
    if "none" not in by or "full" not in by or not moss:
        return None
    cells = []
    for r in (by["none"], by["full"], moss):
        lo, hi = bootstrap_ci(r["trials"])
        cells.append("%.3f [%.3f, %.3f]" % (median(r["trials"]), lo, hi))
    ps = [paired_p(moss["trials"], by["none"]["trials"])[0],
          paired_p(by["full"]["trials"], by["none"]["trials"])[0],
          paired_p(moss["trials"], by["full"]["trials"])[0]]
    return "| %s | %d | %s | %s | %s, C = %d | %.3g | %.3g | %.3g |" % (
        rows[0]["world"], len(moss["trials"]), cells[0], cells[1], cells[2], moss["C"], *ps)


def read_csv(folder, name):
    with open(os.path.join(folder, name)) as f:
        return list(csv.DictReader(f))


def claims(rows, world=""):
    full = [r for r in rows if r["method"] == "full"]
    out = []
    if not full:
        return out
    if all(r["trials"] for r in rows):
        out = paired_claims(rows)
        sizes = sorted({r["C"] for r in rows if r["method"] == "moss"})
        if world == "SQUARE" and 21 in sizes:
            best = min(sizes, key=lambda c: [r for r in rows if r["method"] == "moss"
                                             and r["C"] == c][0]["test_rmse"])
            out.append("MOSS with C = 21 gives the best overall performance (sec. 5.5.2): %s "
                       "(MOSS's lowest test RMSE at C = %d)"
                       % ("holds" if best == 21 else "does not hold", best))
        return out
    full_rmse = full[0]["test_rmse"]
    by = {(r["method"], r["C"]): r for r in rows}
    sizes = sorted({r["C"] for r in rows if r["method"] == "moss"})
    beats = []
    for c in sizes:
        m = by[("moss", c)]["test_rmse"]
        others = [by[(k, c)]["test_rmse"] for k in ("equidistant", "ssm") if (k, c) in by]
        if others:
            beats.append((c, m < min(others)))
    if beats:
        won = [c for c, ok in beats if ok]
        out.append("MOSS beats Equidistant and SSM at every C: %s (MOSS lowest at %d of %d C: %s)"
                   % ("holds" if len(won) == len(beats) else "does not hold", len(won),
                      len(beats), ", ".join(str(c) for c in won) or "none"))
    small = [c for c in sizes if by[("moss", c)]["test_rmse"] <= full_rmse]
    out.append("MOSS with few nodes at least as good as the full map (test RMSE %.3f m): "
               "at C = %s" % (full_rmse, ", ".join(str(c) for c in small) or "no C"))
    if sizes:
        best = min(sizes, key=lambda c: by[("moss", c)]["test_rmse"])
        b = by[("moss", best)]
        out.append("MOSS's map at its best C (C = %d, test RMSE %.3f +- %.3f m) at least as good "
                   "as the full map (%.3f m): %s" % (
                       best, b["test_rmse"], 3 * b["test_rmse_se"], full_rmse,
                       "holds" if b["test_rmse"] <= full_rmse else "does not hold"))
        # Picking C by the test error flatters MOSS; its training error picks too.
        by_train = min(sizes, key=lambda c: (by[("moss", c)]["train_rmse"], c))
        t = by[("moss", by_train)]
        out.append("... at the C its training error picks (C = %d, test RMSE %.3f +- %.3f m): %s"
                   % (by_train, t["test_rmse"], 3 * t["test_rmse_se"],
                      "holds" if t["test_rmse"] <= full_rmse else "does not hold"))
        # Eq. 5.3's error (mean norm) weighs a few large errors less than the RMSE.
        if all(r["test_mean_error"] == r["test_mean_error"] for r in rows):  # not NaN
            bn = min(sizes, key=lambda c: by[("moss", c)]["test_mean_error"])
            n = by[("moss", bn)]
            out.append("... in eq. 5.3's mean error norm (C = %d, %.3f +- %.3f m; full map %.3f "
                       "m): %s" % (bn, n["test_mean_error"], 3 * n["test_mean_error_se"],
                                   full[0]["test_mean_error"],
                                   "holds" if n["test_mean_error"] <= full[0]["test_mean_error"]
                                   else "does not hold"))
        if world == "SQUARE" and 21 in sizes:
            out.append("MOSS with C = 21 gives the best overall performance (sec. 5.5.2): %s "
                       "(MOSS's lowest test RMSE at C = %d)"
                       % ("holds" if best == 21 else "does not hold", best))
    return out


def main():
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawTextHelpFormatter)
    p.add_argument("folder")
    p.add_argument("--nodes_sizes", default="", help="C values drawn in nodes.png (default: 4 smallest)")
    a = p.parse_args()
    rows = read_rows(a.folder)
    world = rows[0]["world"] if rows else "?"
    lines = ["# MOSS on %s" % world, "",
             "| method | C | train RMSE (m) | test RMSE (m) | 3 SE (m) | test mean error (m) | 3 SE (m) "
             "| time (s) | ms / evaluation | nodes |",
             "|---|---|---|---|---|---|---|---|---|---|"]
    for r in sorted(rows, key=lambda r: (r["C"], r["method"])):
        lines.append("| %s | %d | %.3f | %.3f | %.3f | %.3f | %.3f | %.1f | %.2f | %s |" % (
            LABELS.get(r["method"], r["method"]), r["C"], r["train_rmse"], r["test_rmse"],
            3 * r["test_rmse_se"], r["test_mean_error"], 3 * r["test_mean_error_se"],
            r["seconds"], r["ms_per_evaluation"],
            " ".join(map(str, r["nodes"])) if len(r["nodes"]) <= 30 else "(all)"))
    lines += ["", "## The thesis' claims", ""] + ["- " + c for c in claims(rows, world)]
    row = summary_row(rows) if all(r["trials"] for r in rows) else None
    if row:
        head = ["| data | test trials | no map | full map | MOSS | p: MOSS < no map "
                "| p: full < no map | p: MOSS < full |", "|---|---|---|---|---|---|---|---|"]
        lines += ["", "## Summary (median per-trial test RMSE, m, [95% bootstrap CI]; one-sided "
                  "paired p)", ""] + head + [row]
        with open(os.path.join(a.folder, "summary.md"), "w") as f:
            f.write("\n".join(head + [row]) + "\n")
    with open(os.path.join(a.folder, "table.md"), "w") as f:
        f.write("\n".join(lines) + "\n")
    print("\n".join(lines))
    try:
        import matplotlib
        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
    except ImportError:
        print("moss_report: matplotlib is not installed; table only", file=sys.stderr)
        return 0
    fig, ax = plt.subplots(figsize=(7, 4.5))
    for m in METHODS:
        rs = sorted([r for r in rows if r["method"] == m], key=lambda r: r["C"])
        if rs:
            ax.errorbar([r["C"] for r in rs], [r["test_rmse"] for r in rs],
                        yerr=[3 * r["test_rmse_se"] for r in rs], marker="o", capsize=3,
                        label=LABELS[m], color=COLORS[m])
    full = [r for r in rows if r["method"] == "full"]
    if full:
        ax.axhline(full[0]["test_rmse"], color="red", linestyle="--",
                   label="full map (C = %d)" % full[0]["C"])
    none = [r for r in rows if r["method"] == "none"]
    if none:
        ax.axhline(none[0]["test_rmse"], color="black", linestyle=":", label="no map (odometry)")
    ax.set_xlabel("C (map nodes kept)")
    ax.set_ylabel("test RMSE (m)")
    ax.set_title("%s: localization test error (error bars: 3 SE)" % world)
    ax.legend()
    fig.tight_layout()
    for ext in ("png", "svg"):
        fig.savefig(os.path.join(a.folder, "rmse." + ext))
    plt.close(fig)

    walls = read_csv(a.folder, "walls.csv")
    # A real log has no walls: its map nodes' returns stand for them.
    points = read_csv(a.folder, "points.csv") if os.path.exists(
        os.path.join(a.folder, "points.csv")) else []
    nodes = read_csv(a.folder, "map.csv")
    sizes = sorted({r["C"] for r in rows if r["method"] in METHODS})
    if a.nodes_sizes:
        sizes = [int(x) for x in a.nodes_sizes.split(",")]
    else:
        sizes = sizes[:4]
    by = {(r["method"], r["C"]): r for r in rows}
    fig, axes = plt.subplots(len(METHODS), max(1, len(sizes)),
                             figsize=(3.2 * max(1, len(sizes)), 2.6 * len(METHODS)), squeeze=False)
    for i, m in enumerate(METHODS):
        for j, c in enumerate(sizes):
            ax = axes[i][j]
            for w in walls:
                ax.plot([float(w["x1"]), float(w["x2"])], [float(w["y1"]), float(w["y2"])], "k-", lw=1)
            if points:
                ax.plot([float(q["x"]) for q in points[::5]], [float(q["y"]) for q in points[::5]],
                        ",", color="0.3")
            xs = [float(n["x"]) for n in nodes]
            ys = [float(n["y"]) for n in nodes]
            ax.plot(xs, ys, ".", color="0.6", ms=3)
            r = by.get((m, c))
            if r:
                ax.plot([xs[k] for k in r["nodes"]], [ys[k] for k in r["nodes"]], "^",
                        color="green", ms=7)
            ax.set_title("%s C=%d" % (LABELS[m], c), fontsize=9)
            ax.set_aspect("equal")
            ax.set_xticks([])
            ax.set_yticks([])
    fig.tight_layout()
    for ext in ("png", "svg"):
        fig.savefig(os.path.join(a.folder, "nodes." + ext))
    plt.close(fig)
    return 0


if __name__ == "__main__":
    sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "common"))
    import script_errors  # noqa: E402
    sys.exit(script_errors.run("moss_report", main))
