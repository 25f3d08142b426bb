"""Tests of apps/robust/objective_ceiling.py on hand-made hamal_robust
summaries: a cell is one spoiled file at one inlier threshold; a wrong map
(by the bar of hamal_robust_report.py, whatever its status) cheaper than the
clean map under the truncated objective rules its cell out, a dearer one
does not; a right map reported not ok is counted apart from right runs;
summaries without a graded objective are skipped and other JSON ignored.

Run by ctest (tests/CMakeLists.txt, sweep_tools)."""

import contextlib
import io
import json
import os
import sys
import tempfile
import unittest

ROOT = os.path.abspath(os.path.join(os.path.dirname(__file__), "..", ".."))
sys.path.insert(0, os.path.join(ROOT, "apps", "robust"))
import objective_ceiling  # noqa: E402


def summary(dataset, spec, status, ate, tls, clean, probability=0.99, true_off=0,
            false_kept=0, error=""):
    return {"dataset": dataset, "spec": spec, "status": status, "ate_translation": ate,
            "true_switched_off": true_off, "true_loop_closures": 100,
            "false_accepted": false_kept, "false_edges": 100, "tls_objective": tls,
            "tls_objective_clean": clean, "evaluation_error": error,
            "robust": {"gnc_probability": probability, "gnc_threshold": 0.0},
            "spoiling": {"source": "/data/" + dataset.split("-")[0] + ".g2o", "outliers": "100"}}


class ObjectiveCeilingTest(unittest.TestCase):
    def write(self, folder, name, content):
        with open(os.path.join(folder, name), "w") as f:
            json.dump(content, f)

    def run_tool(self, folder, *extra):
        out = io.StringIO()
        with contextlib.redirect_stdout(out):
            self.assertEqual(objective_ceiling.main([folder, *extra]), 0)
        return out.getvalue()

    def test_cells_rows_and_totals(self):
        with tempfile.TemporaryDirectory() as d:
            gnc, group = "aprilsam:robust=gnc", "aprilsam:robust=gnc,gnc_group=on"
            # a: right and ok under gnc; group's wrong map is dearer than the clean one.
            self.write(d, "a1.json", summary("a-random-100-s1", gnc, "ok", 0.01, 100, 100))
            self.write(d, "a2.json", summary("a-random-100-s1", group, "ok", 2.0, 120, 100))
            # b: gnc's wrong map, flagged, is cheaper: the cell is ruled out for both.
            self.write(d, "b1.json", summary("a-random-100-s2", gnc, "uncertain", 0.3, 90, 100,
                                             false_kept=2))
            self.write(d, "b2.json", summary("a-random-100-s2", group, "ok", 0.01, 100, 100))
            # c: the same file at another c2 is another cell; a right map not ok.
            self.write(d, "c1.json", summary("a-random-100-s2", gnc, "uncertain", 0.01, 99, 99,
                                             probability=0.999))
            # skipped and ignored
            self.write(d, "e.json", summary("a-random-100-s3", gnc, "ok", 0.01, 1, 1,
                                            error="no clean optimum"))
            self.write(d, "other.json", {"rows": []})
            runs, skipped = objective_ceiling.load([d])
            self.assertEqual((len(runs), skipped), (5, 1))
            ruled = objective_ceiling.cells_ruled_out(runs)
            self.assertEqual(list(ruled), [("a-random-100-s2", (0.99, 0.0))])
            text = self.run_tool(d, "--cells")
            self.assertIn(f"| all | `{gnc}` | 3 | 1 | 1 | 1 (0) | 1 | 1 of 2 |", text)
            self.assertIn(f"| all | `{group}` | 2 | 1 | 0 | 1 (1) | 1 | 0 of 1 |", text)
            self.assertIn("3 cells, 5 runs (1 summaries without a graded objective skipped); "
                          "the objective prefers a wrong map in 1 cells.", text)
            self.assertIn("- a-random-100-s2: `aprilsam:robust=gnc` ends at a wrong map of "
                          "truncated objective 90, the clean map's 100", text)

    def test_the_bar_is_the_reports(self):
        s = summary("x", "gnc", "uncertain", 0.05, 1, 1, true_off=1, false_kept=1)
        self.assertTrue(objective_ceiling.map_right(s))
        for changed in ({"ate_translation": 0.0501}, {"true_switched_off": 2},
                        {"false_accepted": 2}, {"ate_translation": None}):
            self.assertFalse(objective_ceiling.map_right({**s, **changed}), changed)

    def test_nothing_graded_is_an_error(self):
        with tempfile.TemporaryDirectory() as d:
            self.write(d, "other.json", {"rows": []})
            with self.assertRaises(SystemExit) as e:
                objective_ceiling.main([d])
            self.assertIn("no graded hamal_robust summary", str(e.exception))
            with self.assertRaises(SystemExit) as e:
                objective_ceiling.main([os.path.join(d, "missing")])
            self.assertIn("no such file or directory", str(e.exception))


if __name__ == "__main__":
    unittest.main()
