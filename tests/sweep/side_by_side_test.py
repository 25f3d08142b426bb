"""Tests of plugins/gtsam/side_by_side.py (scripts/isam2.sh's tables and
scale plot) on hand-made results, so that they run without GTSAM: the
aprilsam / iSAM2 ratios, and a run stopped by hamal_bench --time_budget
(the 10^5 world), whose ratio is taken at the poses both runs reached and whose curve stays out
of the slope across worlds.

Run by ctest (tests/CMakeLists.txt, sweep_tools)."""

import contextlib
import csv
import io
import os
import sys
import tempfile
import unittest

ROOT = os.path.abspath(os.path.join(os.path.dirname(__file__), "..", ".."))
sys.path.insert(0, os.path.join(ROOT, "plugins", "gtsam"))
import side_by_side  # noqa: E402

SUMMARY_FIELDS = ["dataset", "backend", "steps", "repeats", "cumulative_seconds",
                  "update_only_seconds", "p99_seconds", "final_chi2", "optimum_chi2",
                  "chi2_ratio", "non_ok_steps", "stopped_by_budget"]


def write_world(results, name, poses, runs):
    """runs: backend -> (seconds per step as a function of the step, steps run,
    stopped). Step i of a world of n poses costs f(i); iSAM2's estimate is a
    third of its step."""
    d = os.path.join(results, name)
    os.makedirs(d)
    with open(os.path.join(d, "machine.txt"), "w") as f:
        f.write("residual: measurement\nrepeats: 1\nload before: 0.1 0.1 0.1\n")
    with open(os.path.join(d, "rows.csv"), "w", newline="") as f:
        w = csv.writer(f)
        w.writerow(["run", "step", "backend", "seconds", "estimate_seconds"])
        for backend, (cost, steps, _) in runs.items():
            for i in range(steps):
                s = cost(i)
                w.writerow([0, i, backend, s, s / 3 if backend == "isam2" else 0])
    with open(os.path.join(d, "summary.csv"), "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=SUMMARY_FIELDS)
        w.writeheader()
        for backend, (cost, steps, stopped) in runs.items():
            total = sum(cost(i) for i in range(steps))
            w.writerow({"dataset": name, "backend": backend, "steps": steps, "repeats": 1,
                        "cumulative_seconds": total,
                        "update_only_seconds": total * (2 / 3 if backend == "isam2" else 1),
                        "p99_seconds": 0.001, "final_chi2": "" if stopped else 10.0,
                        "optimum_chi2": 10.0, "chi2_ratio": "" if stopped else 1.0,
                        "non_ok_steps": 0, "stopped_by_budget": 1 if stopped else 0})


class SideBySide(unittest.TestCase):
    def test_ratios_and_a_budget_stopped_world(self):
        with tempfile.TemporaryDirectory() as results:
            # Step cost linear in the step: cumulative time ~ poses^2, slope 2.
            april = lambda i: 1e-6 * (i + 1)  # noqa: E731
            isam = lambda i: 1e-5 * (i + 1)  # noqa: E731
            write_world(results, "gen100", 100,
                        {"aprilsam": (april, 100, False), "isam2": (isam, 100, False)})
            # A second AprilSAM back-end gets its own ratio (half of aprilsam's).
            half = lambda i: 0.5e-6 * (i + 1)  # noqa: E731
            write_world(results, "gen1000", 1000,
                        {"aprilsam": (april, 1000, False), "aprilsam-top": (half, 1000, False),
                         "isam2": (isam, 1000, False)})
            # The budget stopped iSAM2 after 400 of 10000 steps.
            write_world(results, "gen10000", 10000,
                        {"aprilsam": (april, 10000, False), "isam2": (isam, 400, True)})
            log = io.StringIO()
            with contextlib.redirect_stdout(log):
                side_by_side.main(["side_by_side.py", results])
            with open(os.path.join(results, "side_by_side.md")) as f:
                md = f.read()
        lines = md.splitlines()
        # Whole runs: aprilsam 1/10 of iSAM2's step, 3/20 of its update only.
        gen1000 = next(l for l in lines if l.startswith("| gen1000 | `aprilsam`"))
        self.assertIn("| 0.15; 0.10 |", gen1000)
        top = next(l for l in lines if l.startswith("| gen1000 | `aprilsam-top`"))
        self.assertIn("| 0.08; 0.05 |", top)
        # The stopped run: named as such.
        self.assertTrue(any(l.startswith("| gen10000 (stopped at step 400) | `isam2`")
                            for l in lines), md)
        # ... and the ratio taken at the 400 poses both reached: aprilsam's 1e-6 x
        # 400 x 401 / 2 against iSAM2's ten times that (two thirds without its estimate).
        gen10000 = next(l for l in lines if l.startswith("| gen10000 | `aprilsam`"))
        self.assertIn("| at 400 poses: 0.15; 0.10 |", gen10000)
        # Slopes across worlds: aprilsam over 3 worlds, iSAM2 over the 2 it finished,
        # both ~2 (cumulative ~ n^2); the stopped run would have pulled iSAM2's down.
        isam_slope = next(l for l in lines if l.startswith("| `isam2` |"))
        self.assertIn("| 100, 1000 |", isam_slope)
        self.assertIn("| 2.00 |", isam_slope)
        april_slope = next(l for l in lines if l.startswith("| `aprilsam` |"))
        self.assertIn("| 100, 1000, 10000 |", april_slope)
        self.assertIn("| 2.00 |", april_slope)


if __name__ == "__main__":
    unittest.main()
