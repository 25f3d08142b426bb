"""Tests of the accuracy-for-time frontier with iSAM2 (thesis fig. 3.9d;
plugins/gtsam/frontier.json): hamal_sweep passes a group's plugin
and objective to hamal_bench (--plugin, --residual), stops with a clear
error when the plugin is not built, and hamal_report draws and judges an
iSAM2 series beside AprilSAM's sweeps.

A fake hamal_bench (written below, in a fake build directory) stands in for
the real one, so that these run in CI without GTSAM: it lists the back-ends
an iSAM2 plugin would add, records its command line, and writes rows whose
times and chi2 are set by the back-end's options. Run by ctest
(tests/CMakeLists.txt, sweep_tools)."""

import contextlib
import io
import json
import os
import shutil
import sys
import tempfile
import unittest

ROOT = os.path.abspath(os.path.join(os.path.dirname(__file__), "..", ".."))
sys.path.insert(0, os.path.join(ROOT, "apps", "sweep"))
sys.path.insert(0, os.path.join(ROOT, "apps", "report"))
import hamal_sweep  # noqa: E402
import hamal_report  # noqa: E402

PLUGIN = "plugins/libhamal_gtsam_plugin.so"

# Ten steps; the reference's chi2 at step i is 10 + i. A back-end's whole
# time T and relative error e per step follow from its options: AprilSAM
# T = 0.5 (1 - log10 delta_t), e = 1e-2 delta_t; iSAM2 T = 2 (1 - log10 beta)
# (half of it ISAM2::update, half the estimate), e = fake_error beta.
FAKE_BENCH = r'''#!{python}
import json, math, os, sys
argv = sys.argv[1:]
plugins = [argv[i + 1] for i, a in enumerate(argv) if a == "--plugin"]
if "--list_backends" in argv:
    print("cholesky\n    doc\n    max_iterations=20    doc")
    print("aprilsam\n    doc\n    delta_t=0.1    doc\n    nl_t=100    doc")
    if plugins:
        print("isam2\n    doc\n    relinearize_threshold=0.1    doc\n"
              "    relinearize_skip=10    doc")
    sys.exit(0)
with open(os.environ["FAKE_BENCH_LOG"], "a") as f:
    f.write(json.dumps(argv) + "\n")
spec = argv[argv.index("--backend") + 1]
name, _, opts = spec.partition(":")
o = dict(kv.split("=") for kv in opts.split(",") if kv)
if name == "cholesky":
    total, err, est = 10.0, 0.0, 0.0
elif name == "aprilsam":
    d = float(o["delta_t"])
    total, err, est = 0.5 * (1 - math.log10(d)), 1e-2 * d, 0.0
else:
    b = float(o["relinearize_threshold"])
    total, err = 2 * (1 - math.log10(b)), float(o.get("fake_error", 0.1)) * b
    est = 0.5
with open("rows.csv", "w") as f:
    f.write("run,step,backend,kind,seconds,variables_relinearized,chi2,estimate_seconds\n")
    for i in range(10):
        f.write(f"0,{{i}},\"{{spec}}\",incremental,{{total / 10}},{{3 if name == 'isam2' else 0}},"
                f"{{(10 + i) * (1 + err)}},{{est * total / 10}}\n")
summary = {{"backend": spec, "steps": 10, "cumulative_seconds": total,
           "update_only_seconds": total * (1 - est), "p50_seconds": total / 10,
           "p99_seconds": total / 10, "max_seconds": total / 10, "share_under_10ms": 0.0,
           "share_under_100ms": 0.0, "batch_steps": 0, "final_chi2": 19 * (1 + err),
           "chi2_ratio": 1 + err}}
with open("summary.json", "w") as f:
    json.dump([summary], f)
'''


def frontier_spec(fake_error=0.1, plugin=PLUGIN):
    isam2 = "isam2:relinearize_skip=1" + (f",fake_error={fake_error}" if fake_error != 0.1 else "")
    return {"datasets": {"w": {"generate": 10}},
            "residual": "measurement",
            "groups": [{"name": "main", "backends": ["cholesky", "aprilsam"]},
                       {"name": "delta_t", "backends": ["aprilsam"],
                        "grid": {"delta_t": [1, 0.1, 0.01]}},
                       {"name": "relinearize_threshold", "backends": [isam2], "plugin": plugin,
                        "grid": {"relinearize_threshold": [1, 0.1, 0.01]}}]}


def quiet_sweep(*args, **kwargs):
    with contextlib.redirect_stderr(io.StringIO()):
        return hamal_sweep.sweep(*args, **kwargs)


class FrontierTest(unittest.TestCase):
    def setUp(self):
        self.tmp = tempfile.mkdtemp(prefix="hamal_frontier_test_")
        self.build = os.path.join(self.tmp, "build")
        os.makedirs(os.path.join(self.build, "apps"))
        os.makedirs(os.path.join(self.build, "plugins"))
        self.bench = os.path.join(self.build, "apps", "hamal_bench")
        with open(self.bench, "w") as f:
            f.write(FAKE_BENCH.format(python=sys.executable))
        os.chmod(self.bench, 0o755)
        self.plugin = os.path.join(self.build, PLUGIN)
        open(self.plugin, "w").close()
        self.results = os.path.join(self.tmp, "results")
        self.log = os.path.join(self.tmp, "bench.log")
        os.environ["FAKE_BENCH_LOG"] = self.log

    def tearDown(self):
        shutil.rmtree(self.tmp, ignore_errors=True)
        os.environ.pop("FAKE_BENCH_LOG", None)

    def invocations(self):
        if not os.path.exists(self.log):
            return []
        with open(self.log) as f:
            return [json.loads(line) for line in f]

    def test_group_plugin_and_residual_reach_the_bench(self):
        self.assertEqual(quiet_sweep(frontier_spec(), self.results, self.bench, 1, quiet=True), 0)
        calls = self.invocations()
        self.assertEqual(len(calls), 7)  # main's aprilsam is delta_t=0.1 of the grid
        for argv in calls:
            self.assertEqual(argv[argv.index("--residual") + 1], "measurement")
            spec = argv[argv.index("--backend") + 1]
            if spec.startswith("isam2"):
                # The plugin's path relative to the build dir, made absolute;
                # its defaults resolved from --list_backends with the plugin.
                self.assertEqual(argv[argv.index("--plugin") + 1], self.plugin)
                self.assertIn("relinearize_skip=1", spec)
            else:
                self.assertNotIn("--plugin", argv)
        # Recorded beside the run, and part of its identity.
        isam2_dirs = [d for d in os.listdir(os.path.join(self.results, "w"))
                      if d.startswith("isam2")]
        self.assertEqual(len(isam2_dirs), 3)
        with open(os.path.join(self.results, "w", isam2_dirs[0], "config.json")) as f:
            config = json.load(f)
        self.assertEqual(config["residual"], "measurement")
        self.assertEqual(config["plugins"], [self.plugin])
        self.assertTrue(isam2_dirs[0].split("-")[0].endswith("_measurement"))
        # Resumed: nothing is run again.
        self.assertEqual(quiet_sweep(frontier_spec(), self.results, self.bench, 1, quiet=True), 0)
        self.assertEqual(len(self.invocations()), 7)

    def test_thesis_residual_keeps_the_earlier_commands_and_ids(self):
        run = {"spec": "aprilsam", "dataset_def": {"generate": 10}, "mode": "incremental",
               "chi2_every": 1, "max_steps": 0, "reference": "cholesky", "resolved": {},
               "backend": "aprilsam"}
        defaults = {"aprilsam": {"delta_t": "0.1"}}
        before = hamal_sweep.run_id(run, defaults)[0]
        self.assertEqual(hamal_sweep.run_id(dict(run, residual="thesis"), defaults)[0], before)
        self.assertNotEqual(hamal_sweep.run_id(dict(run, residual="measurement"), defaults)[0],
                            before)
        cmd = hamal_sweep.bench_command(self.bench, dict(run, residual="thesis", plugins=[]))
        self.assertNotIn("--residual", cmd)
        self.assertNotIn("--plugin", cmd)

    def test_dry_run_prints_the_plugin(self):
        err = io.StringIO()
        with contextlib.redirect_stderr(err):
            self.assertEqual(hamal_sweep.sweep(frontier_spec(), self.results, self.bench, 1,
                                               dry_run=True), 0)
        lines = [l for l in err.getvalue().splitlines() if "isam2:" in l]
        self.assertEqual(len(lines), 3)
        for line in lines:
            self.assertIn(f"--plugin {self.plugin} ", line)
            self.assertIn("--residual measurement", line)
        self.assertEqual(self.invocations(), [])

    def test_missing_plugin_is_a_clear_error(self):
        os.remove(self.plugin)
        for dry_run in (False, True):
            with self.assertRaises(SystemExit) as cm:
                quiet_sweep(frontier_spec(), self.results, self.bench, 1, quiet=True,
                            dry_run=dry_run)
            message = str(cm.exception)
            self.assertIn(self.plugin, message)
            self.assertIn("relinearize_threshold", message)  # the group asking for it
            self.assertIn("plugins/gtsam/README.md", message)
        self.assertEqual(self.invocations(), [])
        self.assertFalse(os.path.exists(self.results))  # stopped before anything is written

    def report(self, fake_error):
        self.assertEqual(quiet_sweep(frontier_spec(fake_error), self.results, self.bench, 1,
                                     quiet=True), 0)
        out = os.path.join(self.results, "report")
        with contextlib.redirect_stdout(io.StringIO()):
            path = hamal_report.report(self.results, out, "test")
        with open(path) as f:
            return out, f.read()

    def verdict(self, text, who):
        rows = [l for l in text.splitlines()
                if l.startswith(f"| Beyond some running time, {who} keeps a lower error than "
                                "iSAM2's relinearize_threshold sweep")]
        self.assertEqual(len(rows), 1, text)
        return rows[0].rstrip(" |").rsplit("| ", 1)[1]

    def test_report_judges_aprilsam_against_isam2(self):
        out, text = self.report(fake_error=0.1)
        # AprilSAM (0.5 s, 1e-2), (1 s, 1e-3), (1.5 s, 1e-4); iSAM2, update only,
        # (1 s, 1e-1), (2 s, 1e-2), (3 s, 1e-3): AprilSAM is lower at every time.
        self.assertEqual(self.verdict(text, "AprilSAM (delta_t sweep)"), "**yes**")
        self.assertIn("measurement residual", text)
        self.assertNotIn("neither is part of hamal", text)
        self.assertIn("GTSAM's iSAM2 itself", text)
        self.assertIn("### The accuracy-for-time frontier", text)
        # iSAM2's row in the frontier table: whole step, update only, relinearised variables.
        row = next(l for l in text.splitlines()
                   if l.startswith("| relinearize_threshold: isam2 | relinearize_threshold=0.01 |"))
        self.assertEqual(row.rstrip(" |").split(" | ")[2:7], ["6.000", "3.000", "0.001", "0", "30"])
        # At equal time: the best AprilSAM run within iSAM2's 3 s of updates is delta_t=0.01.
        row = next(l for l in text.splitlines()
                   if l.startswith("| `isam2:relinearize_skip=1,relinearize_threshold=0.01` |"))
        self.assertEqual(row.split(" | ")[4], "0.0001")
        if hamal_report.plt is not None:
            for ext in ("png", "svg"):
                figure = os.path.join(out, f"w_d_time_vs_accuracy.{ext}")
                self.assertGreater(os.path.getsize(figure), 1000)

    def test_report_says_no_when_isam2_is_better(self):
        _, text = self.report(fake_error=1e-6)
        self.assertEqual(self.verdict(text, "AprilSAM (delta_t sweep)"), "**no**")

    def test_report_without_isam2_keeps_its_text(self):
        spec = frontier_spec()
        spec["groups"] = spec["groups"][:2]
        del spec["residual"]
        self.assertEqual(quiet_sweep(spec, self.results, self.bench, 1, quiet=True), 0)
        with contextlib.redirect_stdout(io.StringIO()):
            path = hamal_report.report(self.results, os.path.join(self.results, "r"), "test")
        with open(path) as f:
            text = f.read()
        self.assertIn("neither is part of hamal", text)
        self.assertIn("thesis residual", text)
        self.assertNotIn("accuracy-for-time frontier", text)
        self.assertNotIn("iSAM2's relinearize_threshold", text)


if __name__ == "__main__":
    unittest.main()
