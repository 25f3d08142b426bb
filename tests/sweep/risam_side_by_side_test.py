"""Tests of plugins/risam/risam_side_by_side.py (scripts/risam.sh's runs and
tables) on hand-made run folders, so that they run without GTSAM and riSAM:
a second call runs nothing and only redraws the tables; per-step p99 and
total time come from the rows as apps/bench/percentiles.h computes them; a
failed run is counted, not graded; medians are over the seeds; "right" is
hamal_robust_report.py's bar; a judging world is found without its ".g2o";
N = 0 is one clean cell; hamal's models alone need no riSAM executable.

Run by ctest (tests/CMakeLists.txt, sweep_tools)."""

import contextlib
import csv
import io
import json
import os
import sys
import tempfile
import unittest

ROOT = os.path.abspath(os.path.join(os.path.dirname(__file__), "..", ".."))
sys.path.insert(0, os.path.join(ROOT, "plugins", "risam"))
import risam_side_by_side  # noqa: E402


def write_run(results, name, model, ate, seconds, status="ok", failed=None, true_off=1,
              false_kept=2):
    d = os.path.join(results, "runs", name, model.replace(" ", "_"))
    os.makedirs(d)
    if failed:
        with open(os.path.join(d, "failed.json"), "w") as f:
            json.dump({"status": "failed", "message": failed}, f)
        return
    with open(os.path.join(d, "summary.json"), "w") as f:
        json.dump({"status": status, "ate_translation": ate, "true_switched_off": true_off,
                   "false_accepted": false_kept, "true_loop_closures": 50, "false_edges": 10,
                   "evaluation_error": ""}, f)
    with open(os.path.join(d, "rows.csv"), "w", newline="") as f:
        w = csv.writer(f)
        w.writerow(["run", "step", "backend", "seconds"])
        for i, s in enumerate(seconds):
            w.writerow([0, i, model, s])


class RisamSideBySide(unittest.TestCase):
    def test_percentile_is_hamals(self):
        self.assertEqual(risam_side_by_side.percentile([4, 1, 3, 2], 50), 2.5)
        self.assertAlmostEqual(risam_side_by_side.percentile(list(range(101)), 99), 99)
        self.assertAlmostEqual(risam_side_by_side.percentile([0, 10], 99), 9.9)

    def test_a_second_call_runs_nothing_and_draws_the_tables(self):
        with tempfile.TemporaryDirectory() as results:
            for seed, ate in ((1, 0.001), (2, 0.003)):
                name = f"w-random-10-s{seed}"
                spoiled = os.path.join(results, "spoiled", name + ".g2o")
                os.makedirs(os.path.dirname(spoiled), exist_ok=True)
                for p in (spoiled, spoiled + ".false"):
                    open(p, "w").close()
                write_run(results, name, "aprilsam gnc", ate, [0.001] * 99 + [0.1])
                if seed == 1:
                    write_run(results, name, "riSAM", 2 * ate, [0.002] * 100)
                else:
                    write_run(results, name, "riSAM", None, [], failed="riSAM failed at step 7")
            err = io.StringIO()
            with contextlib.redirect_stdout(io.StringIO()), contextlib.redirect_stderr(err):
                # No hamal_spoil or hamal_robust there: nothing may be run.
                risam_side_by_side.main([results, "--bin_dir", "/nonexistent", "--risam",
                                         "/bin/true", "--datasets", "w", "--policies", "random",
                                         "--outliers", "10", "--seeds", "1,2", "--models",
                                         "aprilsam gnc,riSAM"])
            self.assertIn("[4/4] w-random-10-s2 riSAM: failed", err.getvalue())
            with open(os.path.join(results, "side_by_side.csv"), newline="") as f:
                rows = list(csv.DictReader(f))
            self.assertEqual(len(rows), 4)
            gnc = [r for r in rows if r["model"] == "aprilsam gnc" and r["seed"] == "1"][0]
            self.assertAlmostEqual(float(gnc["seconds"]), 0.199)
            self.assertAlmostEqual(float(gnc["p99_ms"]), 1e3 * (0.001 + 0.01 * 0.099))
            with open(os.path.join(results, "side_by_side.md")) as f:
                table = f.read()
            self.assertIn("| w | 10 | random | aprilsam gnc | 1,2 | 2/2 | 0.002 (0.003) | 1 | 2 |",
                          table)
            self.assertIn("| w | 10 | random | riSAM | 1,2 | 1/2 (failed) | 0.002 (0.002) |", table)

    def test_right_is_the_reports_bar(self):
        with tempfile.TemporaryDirectory() as results:
            # 50 true closures, 10 false edges: 0 false kept and 0 true off are
            # right; 1 true off (2%), 1 false kept (10%), 0.06 m or a status
            # other than ok are not.
            runs = [("aprilsam gnc", 0.01, "ok", 0, 0, 1),
                    ("aprilsam-top gnc", 0.01, "ok", 1, 0, 0),
                    ("aprilsam maxmix", 0.01, "ok", 0, 1, 0),
                    ("aprilsam pcm+gnc", 0.06, "ok", 0, 0, 0),
                    ("riSAM", 0.01, "uncertain", 0, 0, 0)]
            for model, ate, status, true_off, false_kept, _ in runs:
                write_run(results, "w-random-10-s1", model, ate, [0.001], status=status,
                          true_off=true_off, false_kept=false_kept)
            with contextlib.redirect_stdout(io.StringIO()), \
                    contextlib.redirect_stderr(io.StringIO()):
                risam_side_by_side.main([results, "--bin_dir", "/nonexistent", "--risam",
                                         "/nonexistent", "--datasets", "w", "--policies",
                                         "random", "--outliers", "10", "--seeds", "1",
                                         "--redraw"])
            with open(os.path.join(results, "side_by_side.csv"), newline="") as f:
                got = {r["model"]: int(r["right"]) for r in csv.DictReader(f)}
            self.assertEqual(got, {m: want for m, *_, want in runs})
            with open(os.path.join(results, "side_by_side.md")) as f:
                table = f.read()
            self.assertRegex(table, r"\| aprilsam gnc \|.*\| 1/1 \|\n")
            self.assertRegex(table, r"\| riSAM \|.*\| 0/1 \|\n")

    def test_a_judging_world_is_found_without_its_extension(self):
        with tempfile.TemporaryDirectory() as data:
            for name in ("sparse.g2o", "plain"):
                open(os.path.join(data, name), "w").close()
            self.assertEqual(risam_side_by_side.data_file(data, "sparse"),
                             os.path.join(data, "sparse.g2o"))
            self.assertEqual(risam_side_by_side.data_file(data, "sparse.g2o"),
                             os.path.join(data, "sparse.g2o"))
            self.assertEqual(risam_side_by_side.data_file(data, "plain"),
                             os.path.join(data, "plain"))
            self.assertEqual(risam_side_by_side.data_file(data, "intel"),
                             os.path.join(data, "intel.g2o"))

    def test_no_outliers_is_one_clean_cell_per_seed(self):
        self.assertEqual(
            risam_side_by_side.cells_of(["w"], ["random", "random-group"], [0, 100], [1, 2]),
            [("w", "clean", 0, 1), ("w", "clean", 0, 2), ("w", "random", 100, 1),
             ("w", "random", 100, 2), ("w", "random-group", 100, 1),
             ("w", "random-group", 100, 2)])

    def test_init_and_reference_reach_every_grading(self):
        calls = []

        def fake_run(cmd, timeout):
            calls.append(cmd)
            return 1, "stopped here"

        real = risam_side_by_side.run
        risam_side_by_side.run = fake_run
        try:
            with tempfile.TemporaryDirectory() as results:
                args = risam_side_by_side.argparse.Namespace(
                    bin_dir="/b", risam="/r", timeout=None, init="lago",
                    reference="cholesky:max_iterations=100")
                risam_side_by_side.run_one(args, "s.g2o", "aprilsam gnc", "aprilsam:robust=gnc",
                                           os.path.join(results, "a"))
                risam_side_by_side.run = lambda cmd, timeout: (
                    calls.append(cmd) or (0, "") if cmd[0] == "/r" else fake_run(cmd, timeout))
                risam_side_by_side.run_one(args, "s.g2o", "riSAM", None,
                                           os.path.join(results, "r"))
        finally:
            risam_side_by_side.run = real
        graded = [c for c in calls if c[0] == "/b/hamal_robust"]
        self.assertEqual(len(graded), 2)
        for c in graded:
            self.assertEqual(c[c.index("--init") + 1], "lago")
            self.assertEqual(c[c.index("--reference") + 1], "cholesky:max_iterations=100")

    def test_redraw_leaves_out_the_runs_not_there(self):
        with tempfile.TemporaryDirectory() as results:
            write_run(results, "w-random-10-s1", "riSAM", 0.01, [0.002] * 10)
            with contextlib.redirect_stdout(io.StringIO()), \
                    contextlib.redirect_stderr(io.StringIO()):
                risam_side_by_side.main([results, "--bin_dir", "/nonexistent", "--risam",
                                         "/nonexistent", "--datasets", "w", "--policies",
                                         "random", "--outliers", "10", "--seeds", "1,2",
                                         "--redraw"])
            with open(os.path.join(results, "side_by_side.csv"), newline="") as f:
                rows = list(csv.DictReader(f))
            self.assertEqual([(r["seed"], r["model"]) for r in rows], [("1", "riSAM")])

    def test_rpgo_runs_its_harness_graded_as_risam_is(self):
        with tempfile.TemporaryDirectory() as results:
            name = "w-random-10-s1"
            spoiled = os.path.join(results, "spoiled", name + ".g2o")
            os.makedirs(os.path.dirname(spoiled))
            for p in (spoiled, spoiled + ".false"):
                open(p, "w").close()
            calls = os.path.join(results, "calls.txt")
            bin_dir = os.path.join(results, "bin")
            os.makedirs(bin_dir)
            # Fakes that log their arguments: the harness writes its rows,
            # hamal_robust its summary.
            fake = ("#!" + sys.executable + "\nimport json, sys\na = sys.argv\n"
                    f"open({calls!r}, 'a').write(' '.join(a[1:]) + '\\n')\n"
                    "if '--rows' in a and '--estimate' not in a:\n"
                    "    open(a[a.index('--rows') + 1], 'w').write('step,seconds\\n0,0.5\\n')\n"
                    "if '--summary' in a:\n"
                    "    json.dump({'status': 'ok', 'ate_translation': 0.25, 'true_switched_off': 3,"
                    " 'false_accepted': 1}, open(a[a.index('--summary') + 1], 'w'))\n")
            rpgo = os.path.join(bin_dir, "hamal_rpgo_native")
            for exe in (rpgo, os.path.join(bin_dir, "hamal_robust")):
                with open(exe, "w") as f:
                    f.write(fake)
                os.chmod(exe, 0o755)
            with contextlib.redirect_stdout(io.StringIO()), \
                    contextlib.redirect_stderr(io.StringIO()):
                risam_side_by_side.main([results, "--bin_dir", bin_dir, "--risam", "/nonexistent",
                                         "--rpgo", rpgo, "--datasets", "w", "--policies",
                                         "random", "--outliers", "10", "--seeds", "1",
                                         "--models", "Kimera-RPGO"])
            with open(calls) as f:
                harness, grading = f.read().splitlines()
            run_dir = os.path.join(results, "runs", name, "Kimera-RPGO")
            est, dec = os.path.join(run_dir, "estimate.g2o"), os.path.join(run_dir, "decisions.txt")
            self.assertEqual(harness, f"--data {spoiled} --output {est} --decisions {dec} "
                             f"--rows {os.path.join(run_dir, 'rows.csv')}")
            self.assertTrue(grading.startswith(f"--data {spoiled} --estimate {est} --decisions "
                                               f"{dec} --summary"))
            with open(os.path.join(results, "side_by_side.md")) as f:
                self.assertIn("| w | 10 | random | Kimera-RPGO | 1 | 1/1 | 0.25 (0.25) | 3 | 1 "
                              "| 0.5 |", f.read())

    def test_hamals_models_alone_need_no_risam(self):
        with tempfile.TemporaryDirectory() as results:
            write_run(results, "w-random-10-s1", "aprilsam gnc", 0.01, [0.001])
            args = [results, "--bin_dir", "/nonexistent", "--datasets", "w", "--policies",
                    "random", "--outliers", "10", "--seeds", "1"]
            with contextlib.redirect_stdout(io.StringIO()), \
                    contextlib.redirect_stderr(io.StringIO()):
                risam_side_by_side.main(args + ["--models", "aprilsam gnc", "--redraw"])
            self.assertTrue(os.path.isfile(os.path.join(results, "side_by_side.csv")))
            with self.assertRaisesRegex(SystemExit, "--risam \\(not given\\) is not an executable"):
                risam_side_by_side.main(args + ["--models", "aprilsam gnc,riSAM"])

    def test_an_unknown_model_is_an_error(self):
        with tempfile.TemporaryDirectory() as results:
            with self.assertRaises(SystemExit) as e:
                risam_side_by_side.main([results, "--bin_dir", "x", "--risam", "/bin/true",
                                         "--models", "isam2"])
            self.assertIn("unknown model", str(e.exception))


if __name__ == "__main__":
    unittest.main()
