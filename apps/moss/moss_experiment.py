#!/usr/bin/env python3
"""moss_experiment: a MOSS experiment (thesis sec. 5.5, `hamal_moss
experiment`) here or on a Slurm cluster.

With `--executor local` (the default) it is `hamal_moss experiment`: the T
hill climbs of every C on this machine's threads. With `--executor slurm`
MOSS's climbs, hours each at the thesis' K = 1000, become array tasks (one
per C and climb, `hamal_moss experiment --climb t`, each writing its
checkpoint in OUT/climbs/); when all are in, `hamal_moss experiment` runs
here once more: it finds every climb finished, picks the best of each C,
scores it on the test trials and runs the cheap methods (Equidistant, SSM),
writing rows.csv as a local run does (the same selections; the rows'
evaluation counts cover only what that last run evaluated).

Before anything is submitted the folder is verified by hamal_moss itself
(`--verify_only`, apps/common/resumable_results.h): other parameters than
the folder's are refused naming the parameter. Progress, Ctrl-C and attach,
failed/ and the Slurm options are hamal_sweep's (apps/sweep/README.md).

  moss_experiment.py --output DIR [--executor slurm --partition P --time T ...]
      -- --world CORRIDOR --sizes 1-20 --climbs 10 --steps 1000 ...

The flags after `--` are hamal_moss experiment's (`hamal_moss --help`);
with Slurm, --sizes is needed and each task runs on --cpus_per_task threads.
"""

import argparse
import os
import subprocess
import sys

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(os.path.dirname(HERE))
sys.path.insert(0, os.path.join(ROOT, "apps", "sweep"))
import hamal_sweep  # noqa: E402
import resumable_results  # noqa: E402
import slurm_executor  # noqa: E402

slurm_executor.PROGRAM = "moss_experiment"


def parse_sizes(text):
    """'1-20', '6,11,16,21', '1-4,8': the C values (as hamal_moss reads them)."""
    sizes = []
    for piece in filter(None, text.split(",")):
        lo, dash, hi = piece.partition("-")
        try:
            sizes.extend(range(int(lo), int(hi) + 1) if dash else [int(lo)])
        except ValueError:
            raise SystemExit(f"moss_experiment: --sizes: '{piece}' is not a number or a range a-b")
    return sizes


def folder_parameters(out):
    """config.txt's 'name value' lines: what hamal_moss verified the folder with."""
    with open(os.path.join(out, "config.txt")) as f:
        return dict(line.rstrip("\n").partition(" ")[::2] for line in f if line.strip())


def climb_done(task):
    """A climb is in when its checkpoint has reached step K."""
    try:
        with open(task["done"]) as f:
            return int(f.read().split()[0]) >= task["steps"]
    except (OSError, ValueError, IndexError):
        return False


def climb_tasks(moss, flags, out, threads):
    """One task per C and climb whose (moss, C) row is not yet written."""
    given = resumable_results.gflags_parameters(flags)
    if "moss" not in given.get("methods", "moss").split(","):
        return []
    if "sizes" not in given:
        raise SystemExit("moss_experiment: --executor slurm needs --sizes among hamal_moss's "
                         "flags (the C values whose climbs become array tasks)")
    params = folder_parameters(out)
    climbs, steps, seed = int(params["climbs"]), int(params["steps"]), params["seed"]
    rows, _ = resumable_results.read_rows(os.path.join(out, "rows.csv"))
    done = {int(r["C"]) for r in rows if r["method"] == "moss"}
    tasks = []
    for c in parse_sizes(given["sizes"]):
        if c in done:
            continue
        for t in range(climbs):
            tasks.append({
                "label": f"C={c} climb {t}", "steps": steps,
                "done": os.path.join(out, "climbs", f"moss_C{c}_t{t}_s{seed}.climb"),
                "failed": os.path.join(out, "failed", f"C{c}_t{t}"),
                "argv": [moss, "experiment", *flags, "--output", out, "--sizes", str(c),
                         "--climb", str(t), "--threads", str(threads)]})
    return tasks


def main(argv=None):
    argv, flags = hamal_sweep.split_passthrough(sys.argv[1:] if argv is None else argv)
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0],
                                formatter_class=argparse.RawDescriptionHelpFormatter,
                                epilog=__doc__.split("\n\n", 1)[1])
    p.add_argument("--output", "--out", dest="out", required=True, help="the experiment's folder (created; resumed)")
    p.add_argument("--hamal_moss", default=os.environ.get("HAMAL_MOSS") or
                   os.path.join(ROOT, "build", "apps", "hamal_moss"))
    hamal_sweep.add_executor_arguments(p)
    args = p.parse_args(argv)
    slurm = hamal_sweep.executor_options(args)
    moss, out = os.path.abspath(args.hamal_moss), os.path.abspath(args.out)
    if "out" in resumable_results.gflags_parameters(flags):
        raise SystemExit("moss_experiment: give the folder as --output before '--', not after")
    final = [moss, "experiment", *flags, "--output", out]
    if args.executor == "local":
        return subprocess.run(final).returncode
    slurm_executor.require_tools()
    lock = resumable_results.lock(out, f"moss_experiment: another run of {out}")  # noqa: F841
    check = subprocess.run(final + ["--verify_only"], capture_output=True, text=True)
    if check.returncode != 0:
        raise SystemExit(check.stderr.strip() or f"{moss} --verify_only failed")
    tasks = climb_tasks(moss, flags, out, slurm.get("cpus_per_task") or 1)
    status = slurm_executor.run_tasks(
        tasks, out, [os.path.join(ROOT, "apps", "sweep", "slurm_executor.py"), "--command_task"],
        slurm, hamal_sweep.Progress, done=climb_done)
    if status:
        return status
    print("moss_experiment: every climb is in; picking the best of each C here", file=sys.stderr)
    return subprocess.run(final).returncode


if __name__ == "__main__":
    sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "common"))
    import script_errors  # noqa: E402
    sys.exit(script_errors.run("moss_experiment", main))
