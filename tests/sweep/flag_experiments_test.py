"""Tests of FLAG's experiment driver (apps/flag/flag_experiments.py) resuming a
results folder: the folder is verified before it is extended
(apps/sweep/resumable_results.py), so a chunk cut mid-row or mid-field, or
at a line break (rows of its trials missing), is redone, a damaged row or a
missing record of the flags is refused, and other hamal_flag flags than the
folder's are refused naming the flag.

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


if __name__ == "__main__":
    unittest.main()
