"""The Slurm executor of the experiment runners (hamal_sweep, the robust
sweep, FLAG's trials, MOSS's hill climbs): their units of work as Slurm
array jobs.

A runner describes each unit as a task, a JSON object with a "label" (the
progress line's name), "done" (the path that exists once the unit is
complete, written atomically) and "failed" (where its remains go); the
units not yet done are submitted as one `sbatch --array` job (chunked when
there are more than the cluster's MaxArraySize); array task i runs line i of
the tasks file with the runner's task command on the compute node
(hamal_sweep.execute for a sweep's run, `--command_task` below for a unit
that is one command, as a FLAG chunk or a MOSS climb), into the same
results layout as the local executor. The runner then polls squeue (sacct when the cluster keeps
accounting, `scontrol show job` otherwise) and prints the local executor's
progress line. Ctrl-C leaves the jobs running: their ids are recorded in
RESULTS/.slurm/jobs.json, and a later invocation on the same results folder
attaches to them instead of submitting again. A task that ends without its
run (FAILED, CANCELLED, TIMEOUT, OUT_OF_MEMORY, NODE_FAIL) goes to
failed/<dataset>/<run-id>/ with its Slurm log, state and exit code, and is
submitted again by the next invocation.

Two invocations on one results folder are kept apart by the runner's lock
(resumable_results.lock: flock on RESULTS/.lock, held while submitting and
watching) and, should jobs exist that no record names, by the job name
(<runner>-<hash of the results folder>): such jobs stop the submission
instead of being doubled.
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

STATE_DIR = ".slurm"


PROGRAM = "hamal_sweep"  # the runner's name in messages; set by the runner


def die(message):
    raise SystemExit(f"{PROGRAM}: {message}")


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
    return f"{PROGRAM}-" + hashlib.sha1(os.path.abspath(results).encode()).hexdigest()[:8]


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
    path = record_path(results)
    tmp = path + ".tmp"
    with open(tmp, "w") as f:
        json.dump(record, f, indent=1)
    os.replace(tmp, path)


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


def job_script(sub, task_command):
    """The batch script every array task runs: the runner's task command with the
    tasks file ($1); the task reads its line from $SLURM_ARRAY_TASK_ID."""
    path = os.path.join(sub, "job.sh")
    with open(path, "w") as f:
        f.write("#!/bin/sh\n"
                "# Generated by the Slurm executor (apps/sweep/slurm_executor.py): array task\n"
                "# $SLURM_ARRAY_TASK_ID runs that line of the tasks file $1.\n"
                "exec \"${HAMAL_PYTHON:-python3}\" "
                + " ".join(shlex.quote(a) for a in task_command) + " \"$1\"\n")
    os.chmod(path, 0o755)
    return path


def submit(todo, results, task_command, options):
    """One sbatch --array per MaxArraySize tasks; the job ids recorded at once."""
    sub = os.path.join(results, STATE_DIR, time.strftime("%Y%m%d-%H%M%S") + f"-{os.getpid()}")
    os.makedirs(os.path.join(sub, "logs"))
    script = job_script(sub, task_command)
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
            for task in chunk:
                f.write(json.dumps(task) + "\n")
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
    print(f"{PROGRAM}: submitted {len(todo)} runs as Slurm array job {ids}", file=sys.stderr)
    return record


def task_line(tasks):
    """Inside an array task: line $SLURM_ARRAY_TASK_ID of the tasks file, and the
    tag that names its temporary files (<array job>_<index>)."""
    index = int(os.environ["SLURM_ARRAY_TASK_ID"])
    with open(tasks) as f:
        for i, line in enumerate(f):
            if i == index:
                return json.loads(line), f"{os.environ.get('SLURM_ARRAY_JOB_ID', 'job')}_{index}"
    die(f"{tasks} has no task {index}")


def task_runs(record):
    """{(job id, index): task}, read line by line from the tasks files."""
    out = {}
    for job in record["jobs"]:
        with open(job["tasks"]) as f:
            for i, line in enumerate(f):
                out[(job["job_id"], i)] = json.loads(line)
    return out


def is_done(task):
    return os.path.exists(task["done"])


def collect_failure(job, index, task, state, exit_code):
    """A task that ended without its result: what it had written (its "tmp",
    <job>_<index> in place of {task}), its log and Slurm state to its "failed"."""
    failed = task["failed"]
    tmp = task.get("tmp", "").replace("{task}", f"{job['job_id']}_{index}")
    if tmp and os.path.isdir(tmp):  # killed mid-run: what it had written
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


def watch(record, results, progress, poll, done=is_done):
    """Polls until every task of the recorded jobs has ended; returns the failures
    [(task, state, exit code, folder)]."""
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
                print(f"\n{PROGRAM}: Slurm holds job {jid} with reason {reason}: it cannot "
                      f"start as submitted; scancel {jid} and submit again with other "
                      "--partition/--time/--mem/--account", file=sys.stderr)
        if states is not None:
            for key in sorted(left):
                rid = runs[key]["label"]
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
                ok = done(runs[key])
                progress.end(rid, ok)
                if not ok:
                    ended.append(key)
        if ended:
            finals = final_states(sorted({k[0] for k in ended}))
            for key in ended:
                state, code = finals.get(key, ("UNKNOWN", ""))
                if state == "COMPLETED":
                    state = "COMPLETED without its run"
                folder = collect_failure(jobs[key[0]], key[1], runs[key], state, code)
                failures.append((runs[key], state, code, folder))
            ended = []
        progress.show()
        if left:
            time.sleep(poll)
    progress.show(force=True)
    shutil.rmtree(os.path.join(results, STATE_DIR), ignore_errors=True)  # the record too
    return failures


def refuse_local_beside_jobs(results):
    """The local executor does not run beside recorded Slurm jobs of the folder."""
    record = load_record(results)
    if record:
        die(f"Slurm jobs {', '.join(j['job_id'] for j in record['jobs'])} are recorded in "
            f"{record_path(results)}: attach with --executor slurm (or scancel them and "
            "delete that file)")


def refuse_unrecorded_jobs(results):
    """Jobs of this results folder that no record names (an invocation that died
    between sbatch and its record) stop a submission instead of being doubled."""
    states = queued(results)
    stray = sorted({k[0] for k in states}) if states else []
    if stray:
        die(f"Slurm jobs {', '.join(stray)} of {results} are queued but not recorded "
            "there: wait for them or scancel them")


def run_tasks(tasks, results, task_command, options, progress_class, quiet=False,
              cost=lambda task: 1.0, done=is_done):
    """The tasks not yet done as Slurm array jobs, watched to the end (the caller
    holds the results folder's lock); attaches to the jobs recorded by an earlier
    invocation instead of submitting them again. Returns the exit status: 0, 1
    when a task failed, 130 when interrupted (the jobs keep running)."""
    record = load_record(results)
    if not record:
        refuse_unrecorded_jobs(results)
    stream = open(os.devnull, "w") if quiet else sys.stderr
    poll = options.get("poll") or 10
    failures = []
    watched = set()
    try:
        if record:
            attached = task_runs(record)
            watched = {t["done"] for t in attached.values()}
            print(f"{PROGRAM}: attaching to Slurm job "
                  f"{', '.join(j['job_id'] for j in record['jobs'])} ({len(attached)} runs)",
                  file=sys.stderr)
            progress = progress_class({t["label"]: 1.0 for t in attached.values()}, stream=stream)
            failures += watch(record, results, progress, poll, done)
        todo = [t for t in tasks if not done(t) and t["done"] not in watched]
        print(f"{PROGRAM}: {len(tasks)} runs, {len(tasks) - len(todo)} done or just watched, "
              f"{len(todo)} to submit to Slurm -> {results}", file=sys.stderr)
        if todo:
            record = submit(todo, results, task_command, options)
            progress = progress_class({t["label"]: cost(t) for t in todo}, stream=stream)
            failures += watch(record, results, progress, poll, done)
    except KeyboardInterrupt:
        record = load_record(results)
        ids = ", ".join(j["job_id"] for j in record["jobs"]) if record else "-"
        print(f"\n{PROGRAM}: interrupted; Slurm job {ids} keeps running: run the same "
              f"command again to attach (or scancel {ids})", file=sys.stderr)
        return 130
    if not quiet:
        sys.stderr.write("\n")
    for task, state, code, folder in failures:
        print(f"{PROGRAM}: FAILED {task['label']}: Slurm state {state}, "
              f"exit code {code or '?'}; see {folder}", file=sys.stderr)
    return 1 if failures else 0


def run_command_task(tasks):
    """Inside an array task whose unit is one command (the task's "argv"): runs it
    in the task's "cwd" and exits with its status."""
    task, _ = task_line(tasks)
    return subprocess.run(task["argv"], cwd=task.get("cwd"), stdin=subprocess.DEVNULL).returncode


if __name__ == "__main__":
    if len(sys.argv) != 3 or sys.argv[1] != "--command_task":
        die("usage: slurm_executor.py --command_task TASKS (inside a Slurm array task)")
    sys.exit(run_command_task(sys.argv[2]))
