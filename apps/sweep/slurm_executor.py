"""The Slurm executor of hamal_sweep: a sweep's runs as Slurm array jobs.

The runs not yet done are submitted as one `sbatch --array` job (chunked when
there are more than the cluster's MaxArraySize); array task i runs line i of
a tasks file through hamal_sweep.execute on the compute node, into the same
results layout as the local executor (a temporary directory renamed when
complete). The runner then polls squeue (sacct when the cluster keeps
accounting, `scontrol show job` otherwise) and prints the local executor's
progress line. Ctrl-C leaves the jobs running: their ids are recorded in
RESULTS/.slurm/jobs.json, and a later invocation on the same results folder
attaches to them instead of submitting again. A task that ends without its
run (FAILED, CANCELLED, TIMEOUT, OUT_OF_MEMORY, NODE_FAIL) goes to
failed/<dataset>/<run-id>/ with its Slurm log, state and exit code, and is
submitted again by the next invocation.

Two invocations on one results folder are kept apart by hamal_sweep's lock
(flock on RESULTS/.lock, held while submitting and watching) and, should
jobs exist that no record names, by the job name (hamal_sweep-<hash of the
results folder>): such jobs stop the submission instead of being doubled.
"""

import hashlib
import json
import os
import re
import shlex
import shutil
import subprocess
import sys
import time

import atomic_json

STATE_DIR = ".slurm"


def die(message):
    raise SystemExit(f"hamal_sweep: {message}")


def require_tools():
    for tool in ("sbatch", "squeue", "scontrol"):
        if not shutil.which(tool):
            die(f"--executor slurm needs {tool} on PATH (Slurm's client commands, "
                f"Debian: slurm-client); not found in PATH={os.environ.get('PATH', '')}")


def call(cmd, check=True):
    """A Slurm command; its own error text in the message when it refuses."""
    proc = subprocess.run(cmd, capture_output=True, text=True, stdin=subprocess.DEVNULL)
    if check and proc.returncode != 0:
        die(f"{cmd[0]} refused ({' '.join(shlex.quote(c) for c in cmd)}):\n"
            f"{(proc.stderr or proc.stdout).strip()}")
    return proc


def job_name(results):
    return "hamal_sweep-" + hashlib.sha1(os.path.abspath(results).encode()).hexdigest()[:8]


def max_array_size():
    out = call(["scontrol", "show", "config"], check=False).stdout
    m = re.search(r"^MaxArraySize\s*=\s*(\d+)", out, re.M)
    return int(m.group(1)) if m else 1001


def record_path(results):
    return os.path.join(results, STATE_DIR, "jobs.json")


def load_record(results):
    try:
        with open(record_path(results)) as f:
            return json.load(f)
    except FileNotFoundError:
        return None


def save_record(results, record):
    atomic_json.write_json(record_path(results), record)


def expand_indices(text):
    """'2-5%1' or '[1,3-4]' -> [2, 3, 4, 5] or [1, 3, 4]."""
    text = text.strip("[]").split("%")[0]
    out = []
    for part in filter(None, text.split(",")):
        lo, _, hi = part.partition("-")
        out.extend(range(int(lo), int(hi or lo) + 1))
    return out


# Pending reasons that no waiting resolves: the job was accepted (the cluster
# does not set EnforcePartLimits) but can never start as submitted.
HOPELESS = re.compile(r"PartitionTimeLimit|PartitionNodeLimit|PartitionDown|PartitionInactive|"
                      r"AccountNotAllowed|QOSNotAllowed|InvalidAccount|InvalidQOS|"
                      r"MaxWallDurationPerJobLimit|MaxMemPerLimit|MaxCpuPerJobLimit|"
                      r"ReqNodeNotAvail")


def queued(results, reasons=None):
    """{(job id, task index): PENDING | RUNNING | ...} of this results folder's jobs;
    reasons, when given, collects {job id: pending reason} of the hopeless ones."""
    proc = call(["squeue", "-h", f"--name={job_name(results)}", "-o", "%F|%K|%T|%r"],
                check=False)
    if proc.returncode != 0:
        return None  # the controller did not answer: no conclusion this poll
    states = {}
    for line in proc.stdout.splitlines():
        parts = line.strip().split("|")
        if len(parts) != 4 or not parts[1] or parts[1] == "N/A":
            continue
        for i in expand_indices(parts[1]):
            states[(parts[0], i)] = parts[2]
        if reasons is not None and parts[2] == "PENDING" and HOPELESS.search(parts[3]):
            reasons[parts[0]] = parts[3]
    return states


def final_states(job_ids):
    """{(job id, task index): (state, exit code)} of ended tasks: sacct when the
    cluster keeps accounting, else scontrol's records (kept for MinJobAge)."""
    states = {}
    proc = call(["sacct", "-n", "-P", "-X", "-j", ",".join(job_ids), "-o", "JobID,State,ExitCode"],
                check=False) if shutil.which("sacct") else None
    if proc is not None and proc.returncode == 0:
        for line in proc.stdout.splitlines():
            parts = line.split("|")
            m = re.match(r"(\d+)_(\S+)", parts[0]) if len(parts) == 3 else None
            if m:
                for i in expand_indices(m.group(2)):
                    states[(m.group(1), i)] = (parts[1].split()[0], parts[2])
        return states
    for jid in job_ids:
        out = call(["scontrol", "-o", "show", "job", jid], check=False).stdout
        for line in out.splitlines():
            f = dict(kv.split("=", 1) for kv in line.split() if "=" in kv)
            if f.get("ArrayJobId") == jid and re.fullmatch(r"\d+", f.get("ArrayTaskId", "")):
                states[(jid, int(f["ArrayTaskId"]))] = (f.get("JobState", "UNKNOWN"),
                                                        f.get("ExitCode", ""))
    return states


def job_script(sub, results, bench):
    """The batch script every array task runs: one run of the tasks file ($1)."""
    here = os.path.abspath(os.path.join(os.path.dirname(__file__), "hamal_sweep.py"))
    path = os.path.join(sub, "job.sh")
    with open(path, "w") as f:
        f.write("#!/bin/sh\n"
                "# Generated by hamal_sweep --executor slurm: array task $SLURM_ARRAY_TASK_ID\n"
                "# runs that line of the tasks file $1 into the results folder.\n"
                f"exec \"${{HAMAL_PYTHON:-python3}}\" {shlex.quote(here)} --slurm_task \"$1\" "
                f"--results {shlex.quote(results)} --bench {shlex.quote(bench)}\n")
    os.chmod(path, 0o755)
    return path


def submit(todo, results, bench, options, git):
    """One sbatch --array per MaxArraySize runs; the job ids recorded at once."""
    sub = os.path.join(results, STATE_DIR, time.strftime("%Y%m%d-%H%M%S") + f"-{os.getpid()}")
    os.makedirs(os.path.join(sub, "logs"))
    script = job_script(sub, results, bench)
    size = max_array_size()
    record = {"jobs": []}
    resources = []
    for flag in ("partition", "time", "mem", "cpus_per_task", "account"):
        value = options.get(flag)
        if value not in (None, ""):
            resources.append(f"--{flag.replace('_', '-')}={value}")
    resources += shlex.split(options.get("sbatch_args") or "")
    throttle = options.get("max_parallel")
    previous = None
    for k in range(0, len(todo), size):
        chunk = todo[k:k + size]
        tasks = os.path.join(sub, f"tasks-{k // size}.jsonl")
        with open(tasks, "w") as f:
            for run in chunk:
                f.write(json.dumps(dict(run, git=git)) + "\n")
        array = f"0-{len(chunk) - 1}" + (f"%{throttle}" if throttle else "")
        cmd = ["sbatch", "--parsable", f"--job-name={job_name(results)}", f"--array={array}",
               f"--output={os.path.join(sub, 'logs', '%A_%a.out')}", f"--chdir={results}"]
        if throttle and previous:
            cmd.append(f"--dependency=afterany:{previous}")  # the throttle holds across chunks
        proc = call(cmd + resources + [script, tasks])
        previous = proc.stdout.strip().split(";")[0]
        record["jobs"].append({"job_id": previous, "tasks": tasks, "count": len(chunk),
                               "submission": sub})
        save_record(results, record)
    ids = ", ".join(j["job_id"] for j in record["jobs"])
    print(f"hamal_sweep: submitted {len(todo)} runs as Slurm array job {ids}", file=sys.stderr)
    return record


def task_runs(record):
    """{(job id, index): (dataset, run id, spec)}, read line by line from the tasks files."""
    out = {}
    for job in record["jobs"]:
        with open(job["tasks"]) as f:
            for i, line in enumerate(f):
                run = json.loads(line)
                out[(job["job_id"], i)] = (run["dataset"], run["id"], run["spec"])
    return out


def collect_failure(results, job, index, run, state, exit_code):
    """A task that ended without its run: its directory, log and Slurm state to failed/."""
    dataset, rid, _ = run
    failed = os.path.join(results, "failed", dataset, rid)
    tmp = os.path.join(results, dataset, f".tmp-{rid}-{job['job_id']}_{index}")
    if os.path.isdir(tmp):  # killed mid-run: what it had written
        shutil.rmtree(failed, ignore_errors=True)
        os.makedirs(os.path.dirname(failed), exist_ok=True)
        os.rename(tmp, failed)
    os.makedirs(failed, exist_ok=True)
    log = os.path.join(job["submission"], "logs", f"{job['job_id']}_{index}.out")
    if os.path.exists(log):
        shutil.copyfile(log, os.path.join(failed, "slurm.log"))
    with open(os.path.join(failed, "slurm.json"), "w") as f:
        json.dump({"job_id": job["job_id"], "array_task": index, "state": state,
                   "exit_code": exit_code}, f, indent=1)
    return failed


def watch(record, results, progress, poll):
    """Polls until every task of the recorded jobs has ended; returns the failures
    [(dataset, run id, spec, state, exit code, folder)]."""
    runs = task_runs(record)
    jobs = {j["job_id"]: j for j in record["jobs"]}
    left = set(runs)
    running = set()
    ended = []  # tasks gone from the queue without their run
    failures = []
    told = set()
    while left:
        reasons = {}
        states = queued(results, reasons)
        for jid, reason in reasons.items():
            if jid not in told:
                told.add(jid)
                print(f"\nhamal_sweep: Slurm holds job {jid} with reason {reason}: it cannot "
                      f"start as submitted; scancel {jid} and submit again with other "
                      "--partition/--time/--mem/--account", file=sys.stderr)
        if states is not None:
            for key in sorted(left):
                dataset, rid, _ = runs[key]
                state = states.get(key)
                if state in ("RUNNING", "COMPLETING") and key not in running:
                    running.add(key)
                    progress.begin(rid)
                if state is not None:
                    continue
                left.discard(key)
                if key not in running:
                    progress.begin(rid)
                running.discard(key)
                ok = os.path.isdir(os.path.join(results, dataset, rid))
                progress.end(rid, ok)
                if not ok:
                    ended.append(key)
        if ended:
            finals = final_states(sorted({k[0] for k in ended}))
            for key in ended:
                state, code = finals.get(key, ("UNKNOWN", ""))
                if state == "COMPLETED":
                    state = "COMPLETED without its run"
                folder = collect_failure(results, jobs[key[0]], key[1], runs[key], state, code)
                failures.append(runs[key] + (state, code, folder))
            ended = []
        progress.show()
        if left:
            time.sleep(poll)
    progress.show(force=True)
    shutil.rmtree(os.path.join(results, STATE_DIR), ignore_errors=True)  # the record too
    return failures


def unrecorded_jobs(results):
    states = queued(results)
    return sorted({k[0] for k in states}) if states else []
