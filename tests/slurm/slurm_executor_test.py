"""Tests of hamal_sweep's Slurm executor (apps/sweep/slurm_executor.py) against a
real single-node Slurm started for this suite by scripts/local_slurm.sh
(munged, slurmctld and slurmd as plain processes in a temporary folder,
stopped at the end whatever happens): the same results as the local
executor, a task cancelled mid-run reported and resubmitted with nothing
lost or run twice, the array throttle, Ctrl-C then attach, concurrent
invocations, and the messages of bad input; FLAG's trial chunks and MOSS's
hill climbs as array tasks give the local executor's results (the same
daemons: one start for the whole suite).

Skipped, saying why, when Debian's slurmctld, slurmd, slurm-client and munge
are not installed (scripts/setup.sh installs them) or HAMAL_BENCH is not set.
Run by ctest as sweep_slurm (tests/CMakeLists.txt)."""

import contextlib
import csv
import io
import glob
import json
import os
import shutil
import signal
import subprocess
import sys
import tempfile
import time
import unittest

ROOT = os.path.abspath(os.path.join(os.path.dirname(__file__), "..", ".."))
SWEEP = os.path.join(ROOT, "apps", "sweep", "hamal_sweep.py")
LOCAL_SLURM = os.path.join(ROOT, "scripts", "local_slurm.sh")
sys.path.insert(0, os.path.join(ROOT, "apps", "sweep"))
import hamal_sweep  # noqa: E402
import slurm_executor  # noqa: E402

BENCH = os.environ.get("HAMAL_BENCH", "")
PATH = os.environ.get("PATH", "") + ":/usr/sbin:/sbin"
MISSING = [t for t in ("munged", "slurmctld", "slurmd", "sbatch", "squeue")
           if not shutil.which(t, path=PATH)]
SKIP = ("Slurm is not installed (missing " + ", ".join(MISSING) +
        "; Debian: apt-get install slurmctld slurmd slurm-client munge)") if MISSING else (
    "HAMAL_BENCH (the built hamal_bench) is not set" if not os.access(BENCH, os.X_OK) else "")

CLUSTER = {}


def setUpModule():
    if SKIP:
        return
    CLUSTER["dir"] = tempfile.mkdtemp(prefix="hamal_slurm_")
    env = dict(os.environ, PATH=PATH)
    proc = subprocess.run([LOCAL_SLURM, "start", CLUSTER["dir"]], env=env,
                          capture_output=True, text=True)
    if proc.returncode != 0:
        subprocess.run([LOCAL_SLURM, "stop", CLUSTER["dir"]], env=env)
        raise RuntimeError("scripts/local_slurm.sh start failed:\n" + proc.stderr)
    os.environ["SLURM_CONF"] = os.path.join(CLUSTER["dir"], "slurm.conf")
    os.environ["PATH"] = PATH
    # Should this process be killed (a ctest timeout), the daemons stop all the same.
    CLUSTER["watchdog"] = subprocess.Popen(
        ["sh", "-c", 'while kill -0 "$0" 2>/dev/null; do sleep 1; done; "$1" stop "$2"',
         str(os.getpid()), LOCAL_SLURM, CLUSTER["dir"]],
        start_new_session=True, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)


def tearDownModule():
    if "dir" in CLUSTER:
        subprocess.run([LOCAL_SLURM, "stop", CLUSTER["dir"]])
        CLUSTER["watchdog"].kill()
        CLUSTER["watchdog"].wait()
        shutil.rmtree(CLUSTER["dir"], ignore_errors=True)


def six_runs(poses=100):
    return {"datasets": {"w": {"generate": poses, "seed": 3}},
            "groups": [{"name": "main", "backends": ["cholesky", "aprilsam"]},
                       {"name": "delta_t", "backends": ["aprilsam"],
                        "grid": {"delta_t": [0.37, 0.0013, 0.05, 0.2]}}]}


TIMINGS = {"seconds", "linearize_seconds", "order_seconds", "factor_seconds", "solve_seconds",
           "other_seconds", "estimate_seconds", "cumulative_seconds", "max_seconds",
           "p50_seconds", "p90_seconds", "p99_seconds", "update_only_seconds",
           "share_under_100ms", "share_under_10ms"}


def without_timings(run_dir):
    with open(os.path.join(run_dir, "rows.csv")) as f:
        rows = [{k: v for k, v in r.items() if k not in TIMINGS} for r in csv.DictReader(f)]
    with open(os.path.join(run_dir, "summary.json")) as f:
        summary = [{k: v for k, v in s.items() if k not in TIMINGS} for s in json.load(f)]
    return rows, summary


def job_name(results, program):
    return program + "-" + slurm_executor.job_name(results).split("-", 1)[1]


def jobcomp(results, program="hamal_sweep"):
    """Array tasks Slurm ran for this results folder (its job completion log)."""
    name = job_name(results, program)
    with open(os.path.join(CLUSTER["dir"], "jobcomp.txt")) as f:
        return [dict(kv.split("=", 1) for kv in line.split() if "=" in kv)
                for line in f if f"Name={name} " in line]


class ArrayIndexTest(unittest.TestCase):
    def test_squeue_index_expressions(self):
        self.assertEqual(slurm_executor.expand_indices("7"), [7])
        self.assertEqual(slurm_executor.expand_indices("[2-5%1]"), [2, 3, 4, 5])
        self.assertEqual(slurm_executor.expand_indices("1,3-4"), [1, 3, 4])


@unittest.skipIf(SKIP, SKIP)
class SlurmExecutorTest(unittest.TestCase):
    def setUp(self):
        self.tmp = tempfile.mkdtemp(prefix="hamal_slurm_sweep_")
        self.results = os.path.join(self.tmp, "results")
        self.spec_file = os.path.join(self.tmp, "spec.json")

    def tearDown(self):
        subprocess.run(["scancel", f"--name={slurm_executor.job_name(self.results)}"])
        shutil.rmtree(self.tmp, ignore_errors=True)

    def write_spec(self, spec):
        with open(self.spec_file, "w") as f:
            json.dump(spec, f)

    def command(self, *extra, results=None):
        return [sys.executable, SWEEP, self.spec_file, "--results", results or self.results,
                "--bench", BENCH, "--executor", "slurm", "--poll", "0.3", *extra]

    def sweep(self, *extra, results=None, env=None):
        return subprocess.run(self.command(*extra, results=results), capture_output=True,
                              text=True, env=env, timeout=120)

    def runs(self, results=None):
        d = os.path.join(results or self.results, "w")
        return sorted(e for e in os.listdir(d) if not e.startswith("."))

    def test_same_results_as_the_local_executor(self):
        self.write_spec(six_runs())
        local = os.path.join(self.tmp, "local")
        code = subprocess.run([sys.executable, SWEEP, self.spec_file, "--results", local,
                               "--bench", BENCH, "--jobs", "2", "--quiet"],
                              capture_output=True, text=True).returncode
        self.assertEqual(code, 0)
        proc = self.sweep()
        self.assertEqual(proc.returncode, 0, proc.stderr)
        self.assertIn("6/6 runs, 0 running, 0 pending", proc.stderr)
        self.assertEqual(self.runs(), self.runs(local))
        self.assertEqual(len(self.runs()), 6)
        for rid in self.runs():
            self.assertEqual(without_timings(os.path.join(self.results, "w", rid)),
                             without_timings(os.path.join(local, "w", rid)), rid)
            with open(os.path.join(self.results, "w", rid, "config.json")) as f:
                self.assertEqual(json.load(f)["exit_status"], 0)
        self.assertEqual(len(jobcomp(self.results)), 6)
        # Nothing left behind but the runs, the manifest and the lock.
        self.assertEqual(sorted(os.listdir(self.results)), [".lock", "manifest.json", "w"])
        again = self.sweep()
        self.assertIn("0 to submit", again.stderr)
        self.assertEqual(len(jobcomp(self.results)), 6)

    def test_cancelled_task_is_failed_then_resubmitted_alone(self):
        spec = six_runs()
        spec["datasets"]["big"] = {"generate": 700, "seed": 1}
        spec["groups"].append({"name": "slow", "datasets": ["big"], "backends": ["cholesky"]})
        spec["groups"][0]["datasets"] = spec["groups"][1]["datasets"] = ["w"]
        self.write_spec(spec)
        proc = subprocess.Popen(self.command(), stderr=subprocess.PIPE, text=True)
        name = slurm_executor.job_name(self.results)
        deadline = time.time() + 60
        cancelled = None
        while time.time() < deadline and not cancelled:
            # The slow run is the costliest: task 0 of the array. Cancelled once its
            # bench runs (its temporary folder is there): a task cancelled while
            # slurmd is still launching it can escape proctrack/linuxproc and finish.
            if glob.glob(os.path.join(self.results, "big", ".tmp-*_0")):
                out = subprocess.run(["squeue", "-h", f"--name={name}", "-o", "%i|%T"],
                                     capture_output=True, text=True).stdout
                for line in out.split():
                    if line.endswith("_0|RUNNING"):
                        cancelled = line.split("|")[0]
                        subprocess.run(["scancel", cancelled], check=True)
            time.sleep(0.05)
        self.assertTrue(cancelled, "task 0 never ran")
        _, err = proc.communicate(timeout=120)
        self.assertEqual(proc.returncode, 1, err + str(jobcomp(self.results)))
        self.assertIn("Slurm state CANCELLED", err)
        self.assertIn("1 failed", err)
        failed = glob.glob(os.path.join(self.results, "failed", "big", "*", "slurm.json"))
        self.assertEqual(len(failed), 1)
        with open(failed[0]) as f:
            self.assertEqual(json.load(f)["state"], "CANCELLED")
        self.assertEqual(os.listdir(os.path.join(self.results, "big")), [])  # no half run
        kept = {rid: os.path.getmtime(os.path.join(self.results, "w", rid, "config.json"))
                for rid in self.runs()}
        self.assertEqual(len(kept), 6)

        again = self.sweep()
        self.assertEqual(again.returncode, 0, again.stderr)
        self.assertIn("1 to submit", again.stderr)
        self.assertEqual(len(os.listdir(os.path.join(self.results, "big"))), 1)
        self.assertEqual({rid: os.path.getmtime(os.path.join(self.results, "w", rid,
                                                             "config.json"))
                          for rid in self.runs()}, kept)
        # 7 tasks, then the one again: every run ran once, the cancelled one twice.
        self.assertEqual(len(jobcomp(self.results)), 8)

    def test_throttle_of_one_runs_one_task_at_a_time(self):
        spec = six_runs()
        spec["groups"] = spec["groups"][1:]
        spec["groups"][0]["grid"]["delta_t"] = [0.37, 0.0013, 0.05]
        self.write_spec(spec)
        proc = self.sweep("--max_parallel", "1")
        self.assertEqual(proc.returncode, 0, proc.stderr)
        tasks = sorted(jobcomp(self.results), key=lambda t: t["StartTime"])
        self.assertEqual(len(tasks), 3)
        for before, after in zip(tasks, tasks[1:]):
            self.assertLessEqual(before["EndTime"], after["StartTime"])

    def test_interrupted_invocation_is_attached_and_concurrent_one_refused(self):
        self.write_spec(six_runs())
        first = subprocess.Popen(self.command("--max_parallel", "1"), stderr=subprocess.PIPE,
                                 text=True)
        record = slurm_executor.record_path(self.results)
        deadline = time.time() + 30
        while not os.path.exists(record) and time.time() < deadline:
            time.sleep(0.05)
        self.assertTrue(os.path.exists(record))
        # While the first watches: a second invocation is refused by the lock.
        second = self.sweep()
        self.assertNotEqual(second.returncode, 0)
        self.assertIn("another sweep is writing", second.stderr)
        first.send_signal(signal.SIGINT)
        _, err = first.communicate(timeout=30)
        self.assertEqual(first.returncode, 130, err)
        self.assertIn("keeps running", err)
        # The local executor will not run beside the recorded jobs.
        local = subprocess.run([sys.executable, SWEEP, self.spec_file, "--results",
                                self.results, "--bench", BENCH], capture_output=True, text=True)
        self.assertNotEqual(local.returncode, 0)
        self.assertIn("attach with --executor slurm", local.stderr)
        # Two at once attach: one watches, the other is refused; no task is submitted twice.
        a = subprocess.Popen(self.command(), stderr=subprocess.PIPE, text=True)
        b = subprocess.Popen(self.command(), stderr=subprocess.PIPE, text=True)
        err_a, err_b = a.communicate(timeout=120)[1], b.communicate(timeout=120)[1]
        self.assertEqual(sorted([a.returncode, b.returncode]), [0, 1], err_a + err_b)
        self.assertIn("attaching to Slurm job", err_a + err_b)
        self.assertEqual(len(self.runs()), 6)
        self.assertEqual(len(jobcomp(self.results)), 6)

    def test_more_runs_than_max_array_size_are_chunked(self):
        real = slurm_executor.max_array_size
        slurm_executor.max_array_size = lambda: 4
        try:
            with contextlib.redirect_stderr(io.StringIO()) as err:
                code = hamal_sweep.sweep(six_runs(), self.results, BENCH, 1, quiet=True,
                                         executor="slurm", slurm={"max_parallel": 2, "poll": 0.3})
        finally:
            slurm_executor.max_array_size = real
        self.assertEqual(code, 0, err.getvalue())
        self.assertIn("as Slurm array job", err.getvalue())
        self.assertEqual(len(self.runs()), 6)
        tasks = jobcomp(self.results)
        self.assertEqual(sorted(int(t["ArrayTaskId"]) for t in tasks), [0, 0, 1, 1, 2, 3])
        first = [t for t in tasks if t["ArrayTaskId"] == "3"][0]["ArrayJobId"]
        # The second array waits for the first: the throttle holds over both.
        second = [t for t in tasks if t["ArrayJobId"] != first]
        self.assertEqual(len(second), 2)
        self.assertGreaterEqual(min(t["StartTime"] for t in second),
                                max(t["EndTime"] for t in tasks if t["ArrayJobId"] == first))

    def test_robust_sweep_passes_the_executor_on(self):
        apps = os.path.dirname(BENCH)
        tools = [os.path.join(apps, t) for t in ("hamal_generate", "hamal_spoil", "hamal_robust")]
        if not all(os.access(t, os.X_OK) for t in tools):
            self.skipTest(f"hamal_generate, hamal_spoil and hamal_robust are not built in {apps}")
        graph = os.path.join(self.tmp, "w.g2o")
        subprocess.run([tools[0], "--poses", "100", "--output", graph], check=True,
                       capture_output=True)
        with open(self.spec_file, "w") as f:
            json.dump({"datasets": {"w": {"data": graph}},
                       "spoil": {"outliers": [0, 5], "policies": ["random"], "seeds": [1]},
                       "models": ["none", "maxmix"], "timeout": 60,
                       "runs": [{"backend": "cholesky", "mode": "batch"}]}, f)
        proc = subprocess.run(
            [sys.executable, os.path.join(ROOT, "apps", "robust", "hamal_robust_sweep.py"),
             self.spec_file, "--results", self.results, "--bin_dir", apps,
             "--executor", "slurm", "--poll", "0.3"], capture_output=True, text=True, timeout=120)
        self.assertEqual(proc.returncode, 0, proc.stderr)
        self.assertIn("submitted 4 runs as Slurm array job", proc.stderr)
        self.assertEqual(len(jobcomp(self.results)), 4)
        for cell in ("w-clean", "w-random-5-s1"):
            self.assertEqual(len(glob.glob(os.path.join(self.results, cell, "*",
                                                        "summary.json"))), 2)

    def test_bad_input_is_named(self):
        self.write_spec(six_runs())
        no_slurm = self.sweep(env=dict(os.environ, PATH=os.path.join(self.tmp, "nothing")))
        self.assertNotEqual(no_slurm.returncode, 0)
        self.assertIn("needs sbatch on PATH", no_slurm.stderr)
        partition = self.sweep("--partition", "nosuchpartition")
        self.assertNotEqual(partition.returncode, 0)
        self.assertIn("sbatch refused", partition.stderr)
        self.assertIn("Invalid partition name specified", partition.stderr)
        too_long = self.sweep("--partition", "short", "--time", "10")
        self.assertNotEqual(too_long.returncode, 0)
        self.assertIn("Requested time limit is invalid", too_long.stderr)
        self.assertIsNone(slurm_executor.load_record(self.results))
        unknown = subprocess.run([sys.executable, SWEEP, self.spec_file, "--results",
                                  self.results, "--executor", "pbs"], capture_output=True,
                                 text=True)
        self.assertNotEqual(unknown.returncode, 0)
        self.assertIn("unknown --executor 'pbs'", unknown.stderr)
        with self.assertRaises(SystemExit):
            hamal_sweep.sweep(six_runs(), self.results, BENCH, 1, executor="pbs")


FLAG = os.environ.get("HAMAL_FLAG", "")
FLAG_DRIVER = os.path.join(ROOT, "apps", "flag", "flag_experiments.py")


@unittest.skipIf(SKIP, SKIP)
@unittest.skipUnless(os.access(FLAG, os.X_OK), "HAMAL_FLAG (the built hamal_flag) is not set")
class FlagTrialsOnSlurmTest(unittest.TestCase):
    def setUp(self):
        self.tmp = tempfile.mkdtemp(prefix="hamal_slurm_flag_")

    def tearDown(self):
        for chunks in glob.glob(os.path.join(self.tmp, "*", "dynamic", "chunks-*")):
            subprocess.run(["scancel", "--name=" + job_name(chunks, "flag_experiments")])
        shutil.rmtree(self.tmp, ignore_errors=True)

    def driver(self, results, *extra):
        return subprocess.run([sys.executable, FLAG_DRIVER, "dynamic", "--trials", "4",
                               "--chunk", "1", "--results", os.path.join(self.tmp, results),
                               "--hamal-flag", FLAG, *extra], capture_output=True, text=True,
                              timeout=120)

    def test_chunks_as_array_tasks_give_the_local_trials(self):
        local = self.driver("local", "--jobs", "2")
        self.assertEqual(local.returncode, 0, local.stderr)
        slurm = self.driver("slurm", "--executor", "slurm", "--max_parallel", "2",
                            "--poll", "0.3")
        self.assertEqual(slurm.returncode, 0, slurm.stderr)
        self.assertIn("submitted 4 runs as Slurm array job", slurm.stderr)
        self.assertIn("4/4 runs, 0 running, 0 pending", slurm.stderr)
        trials = [os.path.join(self.tmp, d, "dynamic", "trials.csv") for d in ("local", "slurm")]
        with open(trials[0], "rb") as a, open(trials[1], "rb") as b:
            self.assertEqual(a.read(), b.read())
        (chunks,) = glob.glob(os.path.join(self.tmp, "slurm", "dynamic", "chunks-*"))
        self.assertEqual(len(jobcomp(chunks, "flag_experiments")), 4)
        again = self.driver("slurm", "--executor", "slurm", "--poll", "0.3")
        self.assertEqual(again.returncode, 0, again.stderr)
        self.assertIn("0 to submit", again.stderr)
        self.assertEqual(len(jobcomp(chunks, "flag_experiments")), 4)

    def test_a_failed_chunk_goes_to_failed_with_its_state(self):
        proc = self.driver("bad", "--executor", "slurm", "--poll", "0.3", "--trials", "1", "--",
                           "--gate", "-1")
        self.assertEqual(proc.returncode, 1, proc.stderr)
        self.assertIn("Slurm state FAILED", proc.stderr)
        (record,) = glob.glob(os.path.join(self.tmp, "bad", "dynamic", "chunks-*", "failed",
                                           "*", "slurm.json"))
        with open(record) as f:
            self.assertEqual(json.load(f)["state"], "FAILED")
        with open(os.path.join(os.path.dirname(record), "slurm.log")) as f:
            self.assertIn("gate", f.read())


MOSS = os.environ.get("HAMAL_MOSS", "")
MOSS_DRIVER = os.path.join(ROOT, "apps", "moss", "moss_experiment.py")
MOSS_FLAGS = ["--world", "CORRIDOR", "--sizes", "3", "--train", "2", "--test", "2",
              "--climbs", "2", "--steps", "5", "--threads", "1"]
MOSS_TIMINGS = {"seconds", "evaluations", "ms_per_evaluation", "cache_hits", "cache_misses",
                "trials_localized_fraction"}


@unittest.skipIf(SKIP, SKIP)
@unittest.skipUnless(os.access(MOSS, os.X_OK), "HAMAL_MOSS (the built hamal_moss) is not set")
class MossClimbsOnSlurmTest(unittest.TestCase):
    def setUp(self):
        self.tmp = tempfile.mkdtemp(prefix="hamal_slurm_moss_")
        self.out = os.path.join(self.tmp, "slurm")

    def tearDown(self):
        subprocess.run(["scancel", "--name=" + job_name(self.out, "moss_experiment")])
        shutil.rmtree(self.tmp, ignore_errors=True)

    def driver(self, *flags):
        return subprocess.run([sys.executable, MOSS_DRIVER, "--out", self.out, "--hamal_moss",
                               MOSS, "--executor", "slurm", "--poll", "0.3", "--", *flags],
                              capture_output=True, text=True, timeout=120)

    def rows(self, folder):
        with open(os.path.join(folder, "rows.csv")) as f:
            return [{k: v for k, v in r.items() if k not in MOSS_TIMINGS}
                    for r in csv.DictReader(f)]

    def test_climbs_as_array_tasks_pick_the_local_selections(self):
        local = os.path.join(self.tmp, "local")
        subprocess.run([MOSS, "experiment", *MOSS_FLAGS, "--output", local], check=True,
                       capture_output=True)
        proc = self.driver(*MOSS_FLAGS)
        self.assertEqual(proc.returncode, 0, proc.stderr)
        self.assertIn("submitted 2 runs as Slurm array job", proc.stderr)  # T = 2 climbs
        self.assertIn("2/2 runs, 0 running, 0 pending", proc.stderr)
        self.assertEqual(self.rows(self.out), self.rows(local))
        self.assertEqual(len(jobcomp(self.out, "moss_experiment")), 2)
        again = self.driver(*MOSS_FLAGS)
        self.assertEqual(again.returncode, 0, again.stderr)
        self.assertIn("0 to submit", again.stderr)
        self.assertEqual(self.rows(self.out), self.rows(local))
        # Another K is another experiment: refused by name before anything is submitted.
        other = self.driver(*MOSS_FLAGS, "--steps", "6")
        self.assertNotEqual(other.returncode, 0)
        self.assertIn("steps is '5' there and '6' now", other.stderr)
        self.assertEqual(len(jobcomp(self.out, "moss_experiment")), 2)


if __name__ == "__main__":
    unittest.main()
