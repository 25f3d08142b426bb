"""The Python runners' old option spellings (apps/common/old_spellings.py):
read as the new option, with a line on stderr naming it; the runners that
renamed an option accept both."""
import argparse
import contextlib
import io
import os
import sys
import tempfile
import unittest

ROOT = os.path.abspath(os.path.join(os.path.dirname(__file__), "..", ".."))
sys.path.insert(0, os.path.join(ROOT, "apps", "common"))
sys.path.insert(0, os.path.join(ROOT, "apps", "sweep"))
from old_spellings import old_spelling  # noqa: E402
import hamal_sweep  # noqa: E402


class OldSpellingTest(unittest.TestCase):
    def parser(self):
        p = argparse.ArgumentParser(prog="tool")
        p.add_argument("--output", dest="out", default="d")
        old_spelling(p, "--out", "--output")
        p.add_argument("--repeat", type=int, default=1)
        old_spelling(p, "--repeats", "--repeat")
        return p

    def parse(self, argv):
        err = io.StringIO()
        with contextlib.redirect_stderr(err):
            args = self.parser().parse_args(argv)
        return args, err.getvalue()

    def test_the_new_spelling_is_silent(self):
        args, err = self.parse(["--output", "x"])
        self.assertEqual(args.out, "x")
        self.assertEqual(err, "")

    def test_the_old_spelling_is_read_as_the_new_and_names_it(self):
        args, err = self.parse(["--out", "x", "--repeats", "3"])
        self.assertEqual(args.out, "x")
        self.assertEqual(args.repeat, 3)  # the new option's type applies
        self.assertIn("tool: --out is an old spelling; use --output", err)
        self.assertIn("tool: --repeats is an old spelling; use --repeat", err)

    def test_the_old_spelling_is_not_in_the_help(self):
        self.assertNotIn("--out ", self.parser().format_help())

    @unittest.skipUnless(os.path.exists(hamal_sweep.default_bench()), "no hamal_bench built")
    def test_the_sweep_takes_backend_and_its_old_spelling(self):
        for flag in ("--backend", "--backends"):
            with tempfile.TemporaryDirectory() as results:
                out, err = io.StringIO(), io.StringIO()
                with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
                    status = hamal_sweep.main(["--results", results, "--datasets", "w=gen:20",
                                               flag, "cholesky;ceres", "--dry_run", "--quiet"])
                self.assertEqual(status or 0, 0, err.getvalue())
                said = out.getvalue() + err.getvalue()  # the dry run lists the commands
                self.assertIn("--backend cholesky:", said)
                self.assertIn("--backend ceres:", said)
                self.assertEqual("old spelling; use --backend" in err.getvalue(),
                                 flag == "--backends", err.getvalue())

if __name__ == "__main__":
    unittest.main()
