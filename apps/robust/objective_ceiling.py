#!/usr/bin/env python3
"""Which robust runs no solver of the truncated objective could get right
(apps/robust/CEILING.md).

Reads hamal_robust summaries (--summary JSON: of scripts/robust.sh,
scripts/risam.sh or any hand-made run) and groups them into cells: one
spoiled file, one inlier threshold. A run's map is wrong when more than 1%
of the true loop closures are off, more than 1% of the false ones kept, or
the ATE is over 0.05 m (hamal_robust_report.py's bar, whatever the status).
A cell is one where the objective prefers a wrong map when some run in it,
of any model, ends at a wrong map whose truncated objective (each loop
closure's chi2 capped at c2) is below the clean map's: the clean optimum is
then not the objective's minimum, and a solver that finds the minimum is
wrong there. Every other cell is one the objective allows. The figure is a
lower bound on the cells it rules out: a cheaper wrong map that no run
found is not counted.

Writes, per group (the graph spoiled and N) and per model (spec), runs
right (status ok and the map right), right maps reported not ok, wrong
maps, and right among the cells the objective allows; with --cells, one
line per cell. Summaries without a graded objective (an evaluation error,
an older hamal_robust) are counted as skipped.

    apps/robust/objective_ceiling.py RESULTS_DIR_OR_SUMMARY ... [--cells]
"""
import argparse
import collections
import json
import os
import sys

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)
from hamal_robust_report import right  # noqa: E402


def summaries(paths):
    """Every JSON file under the paths (a file is read as it is)."""
    for p in paths:
        if os.path.isfile(p):
            yield p
            continue
        if not os.path.isdir(p):
            raise SystemExit(f"objective_ceiling: {p}: no such file or directory")
        for root, _, files in os.walk(p):
            for name in sorted(files):
                if name.endswith(".json"):
                    yield os.path.join(root, name)


def map_right(s):
    """The map within the report's bar, whatever the status."""
    return right({"status": "ok", "ate": s.get("ate_translation"),
                  "true_rejected": s.get("true_switched_off") or 0,
                  "false_accepted": s.get("false_accepted") or 0,
                  "true_loop_closures": s.get("true_loop_closures") or 0,
                  "false_edges": s.get("false_edges") or 0})


def group_of(s):
    sp = s.get("spoiling") or {}
    source = os.path.basename(sp.get("source") or s.get("dataset") or "?")
    return f"{os.path.splitext(source)[0]}, N {sp.get('outliers', s.get('false_edges', '?'))}"


def load(paths):
    """(runs, skipped): a run is a dict with the fields the tables read."""
    runs, skipped = [], 0
    for path in summaries(paths):
        try:
            with open(path) as f:
                s = json.load(f)
        except (OSError, ValueError):
            continue
        if not isinstance(s, dict) or "tls_objective" not in s or "spec" not in s:
            continue  # not a hamal_robust summary
        if s.get("evaluation_error") or s.get("tls_objective") is None \
                or s.get("tls_objective_clean") is None:
            skipped += 1
            continue
        robust = s.get("robust") or {}
        c2 = (robust.get("gnc_probability"), robust.get("gnc_threshold"))
        runs.append({"cell": (s.get("dataset"), c2), "group": group_of(s), "spec": s["spec"],
                     "status": s.get("status"), "map_right": map_right(s),
                     "tls": s["tls_objective"], "tls_clean": s["tls_objective_clean"],
                     "path": path})
    return runs, skipped


def cells_ruled_out(runs):
    """The cells where some run's wrong map is cheaper than the clean one."""
    out = {}
    for r in runs:
        if not r["map_right"] and r["tls"] < r["tls_clean"] - 1e-9 * abs(r["tls_clean"]):
            best = out.get(r["cell"])
            if best is None or r["tls"] < best["tls"]:
                out[r["cell"]] = r
    return out


def table(runs, ruled_out):
    counts = collections.defaultdict(collections.Counter)
    for r in runs:
        c = counts[(r["group"], r["spec"])]
        c["runs"] += 1
        right = r["map_right"] and r["status"] == "ok"
        c["right"] += right
        c["flagged"] += r["map_right"] and r["status"] != "ok"
        c["wrong"] += not r["map_right"]
        c["wrong_ok"] += not r["map_right"] and r["status"] == "ok"
        if r["cell"] in ruled_out:
            c["ruled_out"] += 1
        else:
            c["allowed"] += 1
            c["right_allowed"] += right
    lines = ["| graph, N | model | runs | right | right map, not ok | wrong (ok) "
             "| objective prefers a wrong map | right of the cells it allows |",
             "|---|---|---|---|---|---|---|---|"]
    total = collections.defaultdict(collections.Counter)
    for (group, spec), c in sorted(counts.items()):
        total[spec].update(c)
        lines.append(f"| {group} | `{spec}` | {c['runs']} | {c['right']} | {c['flagged']} "
                     f"| {c['wrong']} ({c['wrong_ok']}) | {c['ruled_out']} "
                     f"| {c['right_allowed']} of {c['allowed']} |")
    for spec, c in sorted(total.items()):
        lines.append(f"| all | `{spec}` | {c['runs']} | {c['right']} | {c['flagged']} "
                     f"| {c['wrong']} ({c['wrong_ok']}) | {c['ruled_out']} "
                     f"| {c['right_allowed']} of {c['allowed']} |")
    return lines


def main(argv=None):
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0],
                                formatter_class=argparse.RawDescriptionHelpFormatter,
                                epilog=__doc__.split("\n\n", 1)[1])
    p.add_argument("paths", nargs="+", help="summary files or folders holding them")
    p.add_argument("--cells", action="store_true", help="also one line per ruled-out cell")
    args = p.parse_args(argv)
    runs, skipped = load(args.paths)
    if not runs:
        raise SystemExit("objective_ceiling: no graded hamal_robust summary in "
                         + ", ".join(args.paths))
    ruled_out = cells_ruled_out(runs)
    cells = {r["cell"] for r in runs}
    print("\n".join(table(runs, ruled_out)))
    print(f"\n{len(cells)} cells, {len(runs)} runs ({skipped} summaries without a graded "
          f"objective skipped); the objective prefers a wrong map in {len(ruled_out)} cells.")
    if args.cells:
        for cell, r in sorted(ruled_out.items(), key=lambda kv: str(kv[0])):
            print(f"- {cell[0]}: `{r['spec']}` ends at a wrong map of truncated objective "
                  f"{r['tls']:.6g}, the clean map's {r['tls_clean']:.6g}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
