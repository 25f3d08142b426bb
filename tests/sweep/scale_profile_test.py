"""Tests of scripts/scale_profile.py (backends/aprilsam/README.md, "Where the
time goes as the map grows"): a row is filed under its kind of step, the
slope is log-log least squares, and a run on two small worlds gives one table
line per size whose steps add up to the poses."""

import csv
import os
import shutil
import subprocess
import sys
import tempfile
import unittest

ROOT = os.path.abspath(os.path.join(os.path.dirname(__file__), "..", ".."))
sys.path.insert(0, os.path.join(ROOT, "scripts"))
import scale_profile  # noqa: E402

FIELDS = ["step", "kind", "reason", "seconds", "columns_recomputed", "variables_relinearized",
          "linearize_seconds", "order_seconds", "factor_seconds", "solve_seconds", "other_seconds"]


class ScaleProfileTest(unittest.TestCase):
    def setUp(self):
        self.tmp = tempfile.mkdtemp(prefix="scale_profile_")

    def tearDown(self):
        shutil.rmtree(self.tmp, ignore_errors=True)

    def test_rows_are_filed_by_kind_and_phase(self):
        path = os.path.join(self.tmp, "rows.csv")
        with open(path, "w", newline="") as f:
            w = csv.DictWriter(f, FIELDS)
            w.writeheader()
            w.writerow(dict(step=0, kind="batch", reason="first update", seconds=4,
                            columns_recomputed=9, variables_relinearized=3, linearize_seconds=1,
                            order_seconds=1, factor_seconds=1, solve_seconds=1, other_seconds=0))
            w.writerow(dict(step=1, kind="incremental",
                            reason="|L|=12 >= NL_T=10; top re-eliminated: 2 of 4 rows",
                            seconds=2, columns_recomputed=6, variables_relinearized=2,
                            linearize_seconds=0, order_seconds=0, factor_seconds=2,
                            solve_seconds=0, other_seconds=0))
            for step in (2, 3):
                w.writerow(dict(step=step, kind="incremental", reason="no criterion met",
                                seconds=1, columns_recomputed=step, variables_relinearized=0,
                                linearize_seconds=0, order_seconds=0, factor_seconds=0.5,
                                solve_seconds=0.5, other_seconds=0))
        s = scale_profile.summarise(path)
        self.assertEqual((s["batch_n"], s["top_n"], s["incr_n"]), (1, 1, 2))
        self.assertEqual(s["total"], 8)
        self.assertEqual(s["top_factor"], 2)
        self.assertEqual((s["incr_factor"], s["incr_solve"]), (1, 1))
        self.assertEqual(s["incr_cols/step"], 2.5)
        self.assertEqual(s["factor"], 4)

    def test_slope_is_the_log_log_fit(self):
        self.assertAlmostEqual(scale_profile.slope([1, 2, 4, 8], [3, 12, 48, 192]), 2.0)
        self.assertIsNone(scale_profile.slope([1, 2], [0, 1]))

    def test_a_run_on_two_small_worlds(self):
        bench = os.environ.get("HAMAL_BENCH")
        if not bench:
            self.skipTest("HAMAL_BENCH is not set (ctest sets it)")
        build = os.path.dirname(os.path.dirname(bench))
        out = subprocess.run([sys.executable, os.path.join(ROOT, "scripts", "scale_profile.py"),
                              "--sizes", "150,300", "--dir", self.tmp, "--build", build],
                             capture_output=True, text=True, check=True).stdout
        lines = [l for l in out.splitlines() if l.startswith("| 150 ") or l.startswith("| 300 ")]
        self.assertEqual(len(lines), 4)  # one per size in each table
        self.assertEqual(sum(1 for l in out.splitlines() if l.startswith("| slope ")), 2)
        for n in (150, 300):
            s = scale_profile.summarise(os.path.join(self.tmp, "rows{}.csv".format(n)))
            self.assertEqual(s["batch_n"] + s["top_n"] + s["incr_n"], n)


if __name__ == "__main__":
    unittest.main()
