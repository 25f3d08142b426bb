"""Tests of apps/report/hamal_benchmarks.py: the benchmarks document is
written from hamal_bench's summaries, with the provenance of each run, a
dataset measured once is not run again, --write_only redraws the same
document, and a missing dataset file is skipped, saying so.

Run by ctest (tests/CMakeLists.txt, sweep_tools) with HAMAL_BENCH set to
the built hamal_bench; skipped without it."""

import contextlib
import io
import json
import os
import sys
import tempfile
import unittest

ROOT = os.path.abspath(os.path.join(os.path.dirname(__file__), "..", ".."))
sys.path.insert(0, os.path.join(ROOT, "apps", "report"))
import hamal_benchmarks  # noqa: E402

BENCH = os.environ.get("HAMAL_BENCH", "")
HAVE_BENCH = bool(BENCH) and os.access(BENCH, os.X_OK)


@unittest.skipUnless(HAVE_BENCH, "HAMAL_BENCH is not set to a built hamal_bench")
class BenchmarksDocument(unittest.TestCase):
    def test_written_from_the_summaries_resumed_and_redrawn(self):
        with tempfile.TemporaryDirectory() as tmp:
            results, out = os.path.join(tmp, "runs"), os.path.join(tmp, "BENCHMARKS.md")
            args = ["--bench", BENCH, "--datasets", "gen120,absent.g2o", "--data_dir", tmp,
                    "--backend", "aprilsam;cholesky", "--repeat", "1",
                    "--results", results, "--output", out]
            log = io.StringIO()
            with contextlib.redirect_stdout(log):
                self.assertEqual(hamal_benchmarks.main(args), 0)
            self.assertIn("absent.g2o: not in", log.getvalue())
            with open(os.path.join(results, "gen120.json")) as f:
                summary = json.load(f)
            with open(os.path.join(results, "gen120.provenance.json")) as f:
                info = json.load(f)
            for key in ("date", "git_revision", "machine", "command"):
                self.assertIn(key, info)
            with open(out) as f:
                text = f.read()
            self.assertIn("## gen120", text)
            self.assertIn(info["git_revision"], text)
            self.assertIn(info["machine"]["hostname"], text)
            self.assertNotIn("absent.g2o", text)
            for row in summary:  # the table holds the summary's figures
                self.assertIn(f"| {row['backend']} | {row['steps']} |", text)
                self.assertIn(f"{row['final_chi2']:.5f}", text)

            stamp = os.path.getmtime(os.path.join(results, "gen120.json"))
            with contextlib.redirect_stdout(io.StringIO()) as again:
                hamal_benchmarks.main(args)
            self.assertIn("measured already", again.getvalue())
            self.assertEqual(os.path.getmtime(os.path.join(results, "gen120.json")), stamp)

            os.remove(out)
            with contextlib.redirect_stdout(io.StringIO()):
                hamal_benchmarks.main(["--write_only", "--datasets", "gen120",
                                       "--results", results, "--output", out])
            with open(out) as f:
                self.assertEqual(f.read(), text)


if __name__ == "__main__":
    unittest.main()
