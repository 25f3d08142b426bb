"""Tests of the runners' one-line errors (apps/common/script_errors.py): a
folder that cannot be written or a tool that failed is "program: error: PATH:
reason" and exit status 1 from every Python runner and report script, never a
traceback. Root may write a read-only folder, so the unwritable folder here is
one below a regular file."""

import contextlib
import io
import os
import shutil
import subprocess
import sys
import tempfile
import unittest

ROOT = os.path.abspath(os.path.join(os.path.dirname(__file__), "..", ".."))
sys.path.insert(0, os.path.join(ROOT, "apps", "common"))
import script_errors  # noqa: E402

SCRIPTS = {  # script: arguments that read or write below RESULTS
    "apps/sweep/hamal_sweep.py": ["--results", "RESULTS", "--datasets", "w=gen:20",
                                  "--backend", "cholesky", "--bench", "/bin/true"],
    "apps/robust/hamal_robust_report.py": ["RESULTS"],
    "apps/report/hamal_report.py": ["RESULTS"],
    "apps/flag/flag_experiments.py": ["dynamic", "--results", "RESULTS"],
    "apps/moss/moss_report.py": ["RESULTS"],
}


class ScriptErrorsTest(unittest.TestCase):
    def setUp(self):
        self.tmp = tempfile.mkdtemp(prefix="script_errors_")
        self.blocker = os.path.join(self.tmp, "a_file")
        with open(self.blocker, "w") as f:
            f.write("x\n")
        self.empty = os.path.join(self.tmp, "empty")
        os.mkdir(self.empty)

    def tearDown(self):
        shutil.rmtree(self.tmp, ignore_errors=True)

    def test_an_os_error_is_one_line_and_status_1(self):
        def write():
            open(os.path.join(self.blocker, "out.json"), "w")

        with self.assertRaises(OSError):
            write()
        with contextlib.redirect_stderr(io.StringIO()) as err:
            self.assertEqual(script_errors.run("tool", write), 1)
        self.assertEqual(err.getvalue().count("\n"), 1)
        self.assertIn("tool: error: " + self.blocker, err.getvalue())
        error = NotADirectoryError(20, "Not a directory", "/r/x")
        self.assertEqual(script_errors.message("tool", error),
                         "tool: error: /r/x: Not a directory")
        failed = subprocess.CalledProcessError(1, ["hamal_spoil", "--data", "w.g2o"])
        self.assertEqual(script_errors.message("tool", failed),
                         "tool: error: hamal_spoil --data w.g2o: exited with status 1")

    def test_no_runner_prints_a_traceback_where_it_cannot_write(self):
        results = os.path.join(self.blocker, "results")
        for script, arguments in SCRIPTS.items():
            argv = [a.replace("RESULTS", results).replace("EMPTY", self.empty) for a in arguments]
            r = subprocess.run([sys.executable, os.path.join(ROOT, script)] + argv,
                               stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                               timeout=60)
            name = os.path.basename(script)[:-3]
            self.assertNotEqual(r.returncode, 0, f"{script}: {r.stderr}")
            self.assertNotIn("Traceback", r.stderr, script)
            self.assertIn(f"{name}: error: ", r.stderr, f"{script}: {r.stderr}")
            self.assertIn(self.blocker, r.stderr, f"{script}: {r.stderr}")


if __name__ == "__main__":
    unittest.main()
