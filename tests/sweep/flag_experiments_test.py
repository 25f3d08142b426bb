"""Tests of FLAG's experiment driver (apps/flag/flag_experiments.py) resuming a
results folder: the folder is verified before it is extended
(apps/sweep/resumable_results.py), so a chunk cut mid-row or mid-field, or
at a line break (rows of its trials missing), is redone, a damaged row or a
missing record of the flags is refused, and other hamal_flag flags than the
folder's are refused naming the flag. The real-log report's counts of
runs below dead reckoning and of ties (no landmark factor).

Run by ctest (tests/CMakeLists.txt) with HAMAL_FLAG set to the built
hamal_flag; skipped without it."""

import contextlib
import glob
import io
import os
import shutil
import sys
import tempfile
import unittest

ROOT = os.path.abspath(os.path.join(os.path.dirname(__file__), "..", ".."))
sys.path.insert(0, os.path.join(ROOT, "apps", "flag"))
import flag_experiments  # noqa: E402

FLAG = os.environ.get("HAMAL_FLAG", "")


@unittest.skipUnless(FLAG and os.access(FLAG, os.X_OK),
                     "HAMAL_FLAG (the built hamal_flag) is not set")
class FlagResumeTest(unittest.TestCase):
    def setUp(self):
        self.results = tempfile.mkdtemp(prefix="flag_resume_")

    def tearDown(self):
        shutil.rmtree(self.results, ignore_errors=True)

    def run_driver(self, *extra):
        out = io.StringIO()
        with contextlib.redirect_stdout(out):
            status = flag_experiments.main(["dynamic", "--trials", "4", "--chunk", "2", "--jobs",
                                            "2", "--results", self.results,
                                            "--hamal-flag", FLAG, *extra])
        return status, out.getvalue()

    def chunk(self):
        (chunk,) = glob.glob(os.path.join(self.results, "dynamic", "chunks-*", "000001_2.csv"))
        return chunk

    def test_a_torn_chunk_is_redone(self):
        self.assertEqual(self.run_driver()[0], 0)
        chunk = self.chunk()
        with open(chunk) as f:
            whole = f.read()
        for cut in (whole.rindex(",", 0, len(whole) - 1) + 1, len(whole) - 3):
            with open(chunk, "w") as f:
                f.write(whole[:cut])
            status, out = self.run_driver()
            self.assertEqual(status, 0, out)
            self.assertIn("000001_2.csv: its last row is torn; the chunk is redone", out)
            self.assertIn("1 of 2 chunks already done", out)
            with open(chunk) as f:
                self.assertEqual(f.read().count("\n"), whole.count("\n"))

    def test_a_chunk_cut_at_a_line_break_is_redone(self):
        self.assertEqual(self.run_driver()[0], 0)
        chunk = self.chunk()
        with open(chunk) as f:
            whole = f.read()
        lines = whole.splitlines(keepends=True)
        # One arm of the last seed lost, then its whole seed: whole rows either way.
        for keep, why in ((len(lines) - 1, "seed 2 has 1 rows, seed 1 2"),
                          (len(lines) - 2, "no rows of seed 2 (1 of 2 seeds missing)")):
            with open(chunk, "w") as f:
                f.write("".join(lines[:keep]))
            status, out = self.run_driver()
            self.assertEqual(status, 0, out)
            self.assertIn(f"000001_2.csv: {why}; the chunk is redone", out)
            self.assertIn("1 of 2 chunks already done", out)
            with open(chunk) as f:
                self.assertEqual(f.read(), whole)

    def test_a_damaged_row_or_a_missing_record_is_refused(self):
        self.assertEqual(self.run_driver()[0], 0)
        chunk = self.chunk()
        with open(chunk) as f:
            lines = f.readlines()
        lines[1] = lines[1].replace(",", "", 1)
        with open(chunk, "w") as f:
            f.writelines(lines)
        with self.assertRaisesRegex(SystemExit, r"000001_2.csv:2: \d+ fields, the header has"):
            self.run_driver()
        os.remove(os.path.join(os.path.dirname(chunk), "config.json"))
        with self.assertRaisesRegex(SystemExit, r"chunks-\w+/config.json: missing beside"):
            self.run_driver()
        os.remove(os.path.join(self.results, "dynamic", "config.json"))
        with self.assertRaisesRegex(SystemExit, r"dynamic/config.json: missing beside"):
            self.run_driver()

    def test_other_flags_are_refused_by_name(self):
        self.assertEqual(self.run_driver()[0], 0)
        with self.assertRaisesRegex(SystemExit, r"hamal_flag_options.gate is not set there and "
                                                r"'0.7' now"):
            self.run_driver("--", "--gate", "0.7")
        self.assertEqual(len(glob.glob(os.path.join(self.results, "dynamic", "chunks-*"))), 1)

    def test_flags_as_gflags_reads_them(self):
        self.assertEqual(flag_experiments.resumable_results.gflags_parameters(
            ["--gate", "3", "--nopairwise_check", "--seed=4", "--gate=0.5", "--x", "-1"]),
            {"gate": "0.5", "pairwise_check": "false", "seed": "4", "x": "-1"})


def carmen_row(seed, arm, ate, factors):
    """A row of hamal_flag carmen --output as the report reads it."""
    return {"log": "aces.log", "seed": str(seed), "arm": arm, "ate_m": str(ate),
            "factors": "" if arm == "dead reckoning" else str(factors), "poses": "100",
            "odometry_scale": "1", "precision": "1", "recall": "1", "associated_correct": "3",
            "rejected_correct": "0", "lost_steps": "0", "status": "ok"}


class CarmenReportTest(unittest.TestCase):
    """The real-log table counts a run without a landmark factor (dead
    reckoning itself, FLAG = DR) as a tie, apart from the runs below or above
    dead reckoning, and judges 'below dead reckoning on every seed' on the
    runs with a landmark factor."""

    def report(self, flag_loses):
        rows = []
        # seed: (DR, (known ATE, factors), (FLAG ATE, factors))
        for seed, (dr, known, flag) in {1: (0.2, (0.1, 8), (0.1, 5)),
                                        2: (0.15, (0.15, 0), (0.15, 0)),
                                        3: (0.2, (0.1, 4), (0.3 if flag_loses else 0.1, 2))}.items():
            rows += [carmen_row(seed, "dead reckoning", dr, None),
                     carmen_row(seed, "known association", *known),
                     carmen_row(seed, "FLAG", *flag)]
        out = tempfile.mkdtemp(prefix="flag_carmen_report_")
        try:
            md, holds = flag_experiments.report_carmen(rows, out, "carmen_logs")
        finally:
            shutil.rmtree(out, ignore_errors=True)
        return "\n".join(md), holds

    def test_a_run_without_a_landmark_factor_is_a_tie(self):
        md, holds = self.report(flag_loses=True)
        self.assertIn("no landmark factor: FLAG, known |", md)
        # FLAG: below on seed 1, above on 3, no factor on 2; known: below on 1 and 3.
        self.assertIn("| 1 of 2 | 2 of 2 | 1, 1 |", md)
        self.assertIn("aces: ratio met, every seed not met (1 without a landmark factor)", md)
        self.assertFalse(holds)

    def test_ties_alone_do_not_fail_the_every_seed_target(self):
        md, holds = self.report(flag_loses=False)
        self.assertIn("| 2 of 2 | 2 of 2 | 1, 1 |", md)
        self.assertIn("aces: ratio met, every seed met (1 without a landmark factor)", md)
        self.assertTrue(holds)


if __name__ == "__main__":
    unittest.main()
