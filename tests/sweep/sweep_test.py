"""Tests of the ablation tools (apps/sweep/hamal_sweep.py, apps/report/hamal_report.py,
apps/report/nnz_comparison.py): grid expansion and run identity, resuming a
results folder (finished runs kept, half-written ones redone), a tiny
end-to-end sweep on a 100-pose generated world with two back-ends and the
report drawn from it, and the fill-in counts of thesis fig. 3.3.

Run by ctest (tests/CMakeLists.txt) with HAMAL_BENCH set to the built
hamal_bench; the end-to-end tests are skipped without it, the plotting test
without matplotlib (Debian: python3-matplotlib)."""

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
import nnz_comparison  # noqa: E402

BENCH = os.environ.get("HAMAL_BENCH", "")
HAVE_BENCH = bool(BENCH) and os.access(BENCH, os.X_OK)

DEFAULTS = {"aprilsam": {"mode": "adaptive", "delta_t": "0.01", "period": "50"},
            "cholesky": {"max_iterations": "20"}}


def tiny_spec():
    return {"datasets": {"w100": {"generate": 100, "seed": 3}},
            "groups": [{"name": "main", "backends": ["cholesky", "aprilsam"]},
                       {"name": "delta_t", "backends": ["aprilsam"],
                        "grid": {"delta_t": [0.37, 0.0013]}}]}  # not the default


def quiet_sweep(*args, **kwargs):
    with contextlib.redirect_stderr(io.StringIO()):
        return hamal_sweep.sweep(*args, **kwargs)


class GridTest(unittest.TestCase):
    def test_expands_datasets_backends_and_the_cartesian_grid(self):
        spec = {"datasets": {"a": {"generate": 10}, "b": {"data": "/x.g2o", "chi2_every": 7}},
                "groups": [{"name": "g", "backends": ["aprilsam", "aprilsam-periodic:mode=periodic"],
                            "grid": {"delta_t": [1, 0.1], "nl_t": [10, 100, 1000]}}]}
        runs = hamal_sweep.expand(spec)
        self.assertEqual(len(runs), 2 * 2 * 2 * 3)
        specs = {(r["dataset"], r["spec"]) for r in runs}
        self.assertIn(("a", "aprilsam:delta_t=1,nl_t=10"), specs)
        self.assertIn(("b", "aprilsam-periodic:mode=periodic,delta_t=0.1,nl_t=1000"), specs)
        self.assertEqual({r["chi2_every"] for r in runs if r["dataset"] == "b"}, {7})
        self.assertEqual({r["chi2_every"] for r in runs if r["dataset"] == "a"}, {1})

    def test_group_without_grid_is_one_run_per_backend(self):
        runs = hamal_sweep.expand({"datasets": {"a": {"generate": 10}},
                                   "groups": [{"backends": ["cholesky", "ceres:every=5"]}]})
        self.assertEqual([r["spec"] for r in runs], ["cholesky", "ceres:every=5"])
        self.assertEqual([r["params"] for r in runs], [{}, {}])

    def test_unknown_dataset_is_an_error(self):
        with self.assertRaises(ValueError):
            hamal_sweep.expand({"datasets": {}, "groups": [{"datasets": ["x"], "backends": ["a"]}]})

    def test_command_line_grid(self):
        class Args:
            datasets = ["w=gen:500:2"]
            backends = "cholesky;aprilsam"
            grid = ["aprilsam-periodic:period=100,10,1"]
            chi2_every = None
            mode = None
        spec = hamal_sweep.spec_from_args(Args)
        self.assertEqual(spec["datasets"]["w"], {"generate": 500, "seed": 2})
        runs = hamal_sweep.expand(spec)
        self.assertEqual([r["spec"] for r in runs if r["group"] == "period"],
                         ["aprilsam-periodic:period=100", "aprilsam-periodic:period=10",
                          "aprilsam-periodic:period=1"])

    def test_run_id_is_the_resolved_configuration(self):
        def rid(spec, **extra):
            run = {"spec": spec, "dataset_def": {"generate": 100}, "mode": "incremental",
                   "chi2_every": 1, "max_steps": 0, "reference": "cholesky"}
            run.update(extra)
            return hamal_sweep.run_id(run, DEFAULTS)[0]

        # A default written out is the same run; a value written differently too.
        self.assertEqual(rid("aprilsam"), rid("aprilsam:delta_t=0.01"))
        self.assertEqual(rid("aprilsam:delta_t=1"), rid("aprilsam:delta_t=1.0"))
        self.assertNotEqual(rid("aprilsam"), rid("aprilsam:delta_t=0.1"))
        self.assertNotEqual(rid("aprilsam"), rid("aprilsam", chi2_every=10))
        self.assertNotEqual(rid("cholesky"), rid("cholesky", mode="batch"))
        # Batch solves from LAGO are other runs; "odometry" spelled out is not.
        self.assertNotEqual(rid("cholesky", mode="batch"), rid("cholesky", mode="batch", init="lago"))
        self.assertEqual(rid("cholesky", mode="batch"), rid("cholesky", mode="batch", init="odometry"))
        self.assertIn("_from_lago-", rid("cholesky", mode="batch", init="lago"))
        run = {"spec": "cholesky", "dataset_def": {"generate": 100}, "mode": "batch",
               "chi2_every": 0, "max_steps": 0, "reference": "none", "init": "lago",
               "resolved": {}, "backend": "cholesky"}
        cmd = hamal_sweep.bench_command("hamal_bench", run)
        self.assertEqual(cmd[cmd.index("--init") + 1], "lago")
        self.assertTrue(rid("aprilsam:delta_t=0.1").startswith("aprilsam_delta_t=0.1-"))


class PassthroughTest(unittest.TestCase):
    """What a runner keeps and what it hands on after `--` (the first one)."""

    def test_split(self):
        self.assertEqual(hamal_sweep.split_passthrough(["a", "--b", "1"]), (["a", "--b", "1"], []))
        self.assertEqual(hamal_sweep.split_passthrough(["a", "--", "--x", "--", "y"]),
                         (["a"], ["--x", "--", "y"]))
        self.assertEqual(hamal_sweep.split_passthrough(["--"]), ([], []))


@unittest.skipUnless(HAVE_BENCH, "HAMAL_BENCH (the built hamal_bench) is not set")
class SweepTest(unittest.TestCase):
    def setUp(self):
        self.results = tempfile.mkdtemp(prefix="hamal_sweep_test_")

    def tearDown(self):
        shutil.rmtree(self.results, ignore_errors=True)

    def run_dirs(self):
        d = os.path.join(self.results, "w100")
        return sorted(e for e in os.listdir(d) if not e.startswith("."))

    def test_sweep_writes_runs_and_resumes(self):
        self.assertEqual(quiet_sweep(tiny_spec(), self.results, BENCH, 2, quiet=True), 0)
        dirs = self.run_dirs()
        # cholesky, aprilsam, delta_t 0.37, delta_t 0.0013.
        self.assertEqual(len(dirs), 4)
        for d in dirs:
            path = os.path.join(self.results, "w100", d)
            with open(os.path.join(path, "summary.json")) as f:
                summary = json.load(f)[0]
            self.assertEqual(summary["steps"], 100)
            with open(os.path.join(path, "config.json")) as f:
                config = json.load(f)
            for key in ("git_revision", "machine", "command", "resolved_options",
                        "peak_rss_kb", "started"):
                self.assertIn(key, config)
            self.assertGreater(config["peak_rss_kb"], 0)
            self.assertTrue(config["binaries"])
            # The bench ran with every resolved option spelled out.
            spec = config["command"][config["command"].index("--backend") + 1]
            for key, value in config["resolved_options"].items():
                self.assertIn(f"{key}={value}", spec)
            self.assertEqual(config["exit_status"], 0)

        # Interrupted: one run half-written, one run's directory never renamed.
        kept = os.path.join(self.results, "w100", dirs[0])
        kept_mtime = os.path.getmtime(os.path.join(kept, "config.json"))
        lost = dirs[1]
        shutil.move(os.path.join(self.results, "w100", lost),
                    os.path.join(self.results, "w100", f".tmp-{lost}-99999"))
        os.remove(os.path.join(self.results, "w100", f".tmp-{lost}-99999", "summary.json"))
        self.assertEqual(quiet_sweep(tiny_spec(), self.results, BENCH, 2, quiet=True), 0)
        self.assertEqual(self.run_dirs(), dirs)
        self.assertFalse(any(e.startswith(".tmp-")
                             for e in os.listdir(os.path.join(self.results, "w100"))))
        self.assertEqual(os.path.getmtime(os.path.join(kept, "config.json")), kept_mtime)
        self.assertTrue(os.path.exists(os.path.join(self.results, "w100", lost, "summary.json")))

        # Everything done: nothing runs.
        runs, unique = hamal_sweep.plan(tiny_spec(), self.results, BENCH,
                                        hamal_sweep.backend_defaults(BENCH))
        self.assertTrue(all(r["done"] for r in unique))

    def test_failed_run_is_kept_apart_and_retried(self):
        spec = {"datasets": {"w100": {"generate": 100}},
                "groups": [{"name": "main", "backends": ["cholesky:max_iterations=-3"]}]}
        err = io.StringIO()
        with contextlib.redirect_stderr(err):
            self.assertEqual(hamal_sweep.sweep(spec, self.results, BENCH, 1, quiet=True), 1)
        # The sweep's line says why, from the tool's own error in the log.
        self.assertRegex(err.getvalue(), r"FAILED w100/.*: hamal_bench: error: .*max_iterations")
        self.assertEqual(self.run_dirs(), [])
        self.assertTrue(os.listdir(os.path.join(self.results, "failed", "w100")))

    def one_run(self):
        spec = {"datasets": {"w100": {"generate": 100, "seed": 3}},
                "groups": [{"name": "main", "backends": ["cholesky"]}]}
        self.assertEqual(quiet_sweep(spec, self.results, BENCH, 1, quiet=True), 0)
        (rid,) = self.run_dirs()
        return spec, os.path.join(self.results, "w100", rid)

    def test_a_torn_rows_file_is_redone(self):
        spec, run = self.one_run()
        rows = os.path.join(run, "rows.csv")
        with open(rows) as f:
            whole = f.read()
        # Cut mid-row (after a field's comma) and mid-field (inside a number).
        for cut in (whole.rindex(",", 0, len(whole) - 1) + 1, len(whole) - 3):
            with open(rows, "w") as f:
                f.write(whole[:cut])
            err = io.StringIO()
            with contextlib.redirect_stderr(err):
                self.assertEqual(hamal_sweep.sweep(spec, self.results, BENCH, 1, quiet=True), 0)
            self.assertIn("rows.csv ends in a torn row", err.getvalue())
            self.assertIn("1 to run", err.getvalue())
            with open(rows) as f:
                self.assertEqual(f.read().count("\n"), whole.count("\n"))
            self.assertTrue(os.listdir(os.path.join(self.results, "failed", "w100")))

    def test_a_rows_file_cut_at_a_line_break_is_redone(self):
        spec, run = self.one_run()
        rows = os.path.join(run, "rows.csv")
        with open(rows) as f:
            whole = f.read()
        with open(rows, "w") as f:
            f.write(whole[:whole.rstrip("\n").rfind("\n") + 1])  # the last row lost whole
        err = io.StringIO()
        with contextlib.redirect_stderr(err):
            self.assertEqual(hamal_sweep.sweep(spec, self.results, BENCH, 1, quiet=True), 0)
        self.assertIn(f"rows.csv has {whole.count(chr(10)) - 2} rows, the run wrote "
                      f"{whole.count(chr(10)) - 1}", err.getvalue())
        self.assertIn("1 to run", err.getvalue())
        with open(rows) as f:
            self.assertEqual(f.read().count("\n"), whole.count("\n"))

    def test_a_damaged_row_or_a_missing_config_is_refused(self):
        spec, run = self.one_run()
        rows = os.path.join(run, "rows.csv")
        with open(rows) as f:
            lines = f.readlines()
        lines[2] = lines[2].replace(",", "", 1)
        with open(rows, "w") as f:
            f.writelines(lines)
        with self.assertRaisesRegex(SystemExit, r"rows.csv:3: \d+ fields, the header has"):
            quiet_sweep(spec, self.results, BENCH, 1, quiet=True)
        os.remove(os.path.join(run, "config.json"))
        with self.assertRaisesRegex(SystemExit, r"config.json: missing beside the run's results"):
            quiet_sweep(spec, self.results, BENCH, 1, quiet=True)

    def test_a_changed_parameter_is_refused_by_name(self):
        spec, run = self.one_run()
        other = json.loads(json.dumps(spec))
        other["datasets"]["w100"]["seed"] = 4
        with self.assertRaisesRegex(SystemExit, r"another spec \(datasets.w100.seed is 3 "
                                                r"there and 4 now\)"):
            quiet_sweep(other, self.results, BENCH, 1, quiet=True)
        self.assertEqual(len(self.run_dirs()), 1)  # nothing merged
        config = os.path.join(run, "config.json")
        with open(config) as f:
            recorded = json.load(f)
        recorded["identity"]["options"]["max_iterations"] = "7.0"
        with open(config, "w") as f:
            json.dump(recorded, f)
        with self.assertRaisesRegex(SystemExit, r"options.max_iterations is '7.0' there"):
            quiet_sweep(spec, self.results, BENCH, 1, quiet=True)

    @unittest.skipIf(hamal_report.plt is None, "matplotlib is not installed: no plots to test")
    def test_report_draws_every_figure(self):
        self.assertEqual(quiet_sweep(tiny_spec(), self.results, BENCH, 2, quiet=True), 0)
        out = os.path.join(self.results, "report")
        with contextlib.redirect_stdout(io.StringIO()):
            path = hamal_report.report(self.results, out, "test")
        with open(path) as f:
            text = f.read()
        for fig in ("a_cumulative_time", "b_relative_chi2", "c_step_time_cdf",
                    "d_time_vs_accuracy"):
            for ext in ("png", "svg"):
                f = os.path.join(out, f"w100_{fig}.{ext}")
                self.assertTrue(os.path.getsize(f) > 1000, f)
            self.assertIn(f"w100_{fig}.png", text)
        self.assertTrue(os.path.exists(os.path.join(out, "nnz.png")))
        self.assertIn("thesis claim", text)
        self.assertIn("Sweep `delta_t`", text)


    @unittest.skipIf(hamal_report.plt is None, "matplotlib is not installed: no plots to test")
    def test_report_gives_a_verdict_per_aprilsam_sweep(self):
        # The delta_T sweep alone is held at a plateau by NL_T: the report
        # judges each AprilSAM sweep (delta_T, NL_T) against the periodic one.
        spec = {"datasets": {"w100": {"generate": 100, "seed": 3}},
                "groups": [{"name": "main", "backends": ["cholesky", "aprilsam"]},
                           {"name": "delta_t", "backends": ["aprilsam"],
                            "grid": {"delta_t": [0.37, 0.0013]}},
                           {"name": "nl_t", "backends": ["aprilsam"],
                            "grid": {"nl_t": [100, 1]}},
                           {"name": "period", "backends": ["aprilsam-periodic"],
                            "grid": {"period": [10, 5]}}]}
        self.assertEqual(quiet_sweep(spec, self.results, BENCH, 2, quiet=True), 0)
        out = os.path.join(self.results, "report")
        with contextlib.redirect_stdout(io.StringIO()):
            path = hamal_report.report(self.results, out, "test")
        with open(path) as f:
            text = f.read()
        self.assertIn("AprilSAM (delta_t sweep) keeps a lower error", text)
        self.assertIn("AprilSAM (nl_t sweep) keeps a lower error", text)
        self.assertIn("Sweep `nl_t`", text)


class ReportMathTest(unittest.TestCase):
    def test_lower_error_past_some_point(self):
        # Mine is worse when cheap, better from t = 3 on.
        mine = [(1, 1.0), (3, 0.01), (10, 0.001)]
        other = [(0.5, 0.5), (2, 0.1), (8, 0.05)]
        self.assertEqual(hamal_report.lower_error_past_some_point(mine, [other]), 3)
        self.assertIsNone(hamal_report.lower_error_past_some_point(
            [(1, 1.0), (10, 0.5)], [[(0.5, 0.1)]]))

    def test_slope_of_a_power_law(self):
        xs = [1e4, 1e5, 1e6]
        self.assertAlmostEqual(hamal_report.fit_slope(xs, [3e-6 * x ** 1.5 for x in xs]), 1.5)


class NnzTest(unittest.TestCase):
    def test_fig_3_3_counts(self):
        r = nnz_comparison.compute()
        # 294 factors x 3 rows + the prior's 3, over 100 x 3 columns.
        self.assertEqual((r["rows"], r["columns"]), (885, 300))
        self.assertEqual(r["nnz_A"], 294 * 3 * 6 + 9)
        self.assertEqual(len(r["qr"]), 300)
        # The same R at the end; QR never below Cholesky, and well above at its peak.
        self.assertEqual(r["qr"][-1], r["cholesky"][-1])
        self.assertTrue(all(q >= c for q, c in zip(r["qr"], r["cholesky"])))
        self.assertGreater(max(r["qr"]), 2 * max(r["cholesky"]))
        # R of a band of width 3 nodes: per node 9 + 3 x 9 above-diagonal entries, fewer at the end.
        self.assertEqual(r["cholesky"][-1], r["nnz_triu_AtA"])

    def test_counts_of_a_tiny_graph_by_hand(self):
        # Two scalar columns, rows {0}, {0,1}, {1}: QR column 0 merges rows 0,1 -> R row {0,1},
        # one row {1} left plus row {1}: 2 + 1 + 1 = 4; column 1: R row {1}: 2 + 1 = 3.
        rows = [{0}, {0, 1}, {1}]
        self.assertEqual(nnz_comparison.householder_qr_counts(rows, 2), [4, 3])
        self.assertEqual(nnz_comparison.cholesky_counts(rows, 2), [3, 3])


if __name__ == "__main__":
    unittest.main()
