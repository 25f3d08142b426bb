"""Tests of scripts/step_tail.py (backends/aprilsam/TAIL.md): a slow step is
filed under its kind (full batch, top re-elimination, incremental step), a
graph's name and its own flags come from its argument, and a run on a small
generated world writes one table line and is not run again."""

import csv
import os
import shutil
import subprocess
import sys
import tempfile
import unittest

ROOT = os.path.abspath(os.path.join(os.path.dirname(__file__), "..", ".."))
sys.path.insert(0, os.path.join(ROOT, "scripts"))
import step_tail  # noqa: E402

FIELDS = ["run", "step", "backend", "kind", "reason", "seconds", "columns_recomputed"]


class StepTailTest(unittest.TestCase):
    def setUp(self):
        self.tmp = tempfile.mkdtemp(prefix="step_tail_")

    def tearDown(self):
        shutil.rmtree(self.tmp, ignore_errors=True)

    def test_slow_steps_are_filed_by_kind(self):
        path = os.path.join(self.tmp, "rows.csv")
        rows = [("0", "batch", "first update", 0.020, 3),
                ("0", "incremental", "|L|=12 >= NL_T=10; top re-eliminated: 40 of 90 rows", 0.015, 40),
                ("0", "incremental", "no criterion met", 0.011, 7),
                ("0", "incremental", "no criterion met", 0.001, 2),
                ("1", "batch", "first update", 0.5, 3)]  # a repeat: not counted
        with open(path, "w", newline="") as f:
            w = csv.DictWriter(f, FIELDS)
            w.writeheader()
            for i, (run, kind, reason, s, cols) in enumerate(rows):
                w.writerow(dict(run=run, step=i, backend="b", kind=kind, reason=reason, seconds=s,
                                columns_recomputed=cols))
        t = step_tail.tail_of(path, 0.010)["b"]
        self.assertEqual((t["batch"], t["top"], t["incr"]), (1, 1, 1))
        self.assertEqual(step_tail.kind_of(t["worst"]), "batch")
        self.assertEqual(float(t["worst"]["seconds"]), 0.020)

    def test_graph_names(self):
        self.assertEqual(step_tail.graph_name("../d/M3500.toro"), "M3500")
        self.assertEqual(step_tail.graph_name("gen:20000"), "gen20000")
        self.assertEqual(step_tail.graph_name("w=../d/w20000.txt --format=gtsam"), "w")
        self.assertEqual(step_tail.graph_name("../d/w20000.txt --format=gtsam"), "w20000")

    def test_a_run_on_a_small_world_resumes(self):
        bench = os.environ.get("HAMAL_BENCH")
        if not bench:
            self.skipTest("HAMAL_BENCH is not set (ctest sets it)")
        build = os.path.dirname(os.path.dirname(bench))
        cmd = [sys.executable, os.path.join(ROOT, "scripts", "step_tail.py"), "--dir", self.tmp,
               "--build", build, "gen:200"]
        out = subprocess.run(cmd, capture_output=True, text=True, check=True)
        self.assertIn("running gen200", out.stderr)
        self.assertEqual(sum(1 for l in out.stdout.splitlines() if l.startswith("| gen200 |")), 1)
        with open(os.path.join(self.tmp, "tail.csv")) as f:
            (line,) = list(csv.DictReader(f))
        self.assertEqual(int(line["poses"]), 200)
        self.assertLessEqual(float(line["p50_ms"]), float(line["p99_ms"]))
        self.assertLessEqual(float(line["p99_ms"]), float(line["max_ms"]))
        again = subprocess.run(cmd, capture_output=True, text=True, check=True)
        self.assertNotIn("running", again.stderr)  # the summary exists: not run again
        self.assertEqual(again.stdout, out.stdout)


if __name__ == "__main__":
    unittest.main()
