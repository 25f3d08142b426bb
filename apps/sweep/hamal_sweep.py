#!/usr/bin/env python3
"""hamal_sweep: ablation sweeps over datasets x back-ends x option values.

The runs behind the thesis' evaluation (sec. 3.5, figs. 3.8 and 3.9) and the
scale study: each run is one hamal_bench process for one dataset and one
back-end spec under the thesis protocol (docs/PROTOCOL.md), written to
results/<dataset>/<run-id>/ with

  rows.csv       every step (time, kind, chi2 at the --chi2_every steps)
  summary.json   hamal_bench's summary row
  config.json    the exact command, spec, resolved options, git revision,
                 machine, date, wall time and peak memory (ru_maxrss)
  log.txt        hamal_bench's output

A run is made in a temporary directory and renamed when it is complete, so a
sweep killed half-way loses no finished run and redoes the half-written ones
when started again; a finished run is never redone. Before a folder is
extended it is verified (resumable_results.py): a run whose config.json is
missing or names other parameters, a damaged row, or a dataset name the
folder's manifest defines otherwise is refused, naming the file and line or
the parameter; a run whose rows.csv ends in a torn row is moved to failed/
and redone. The run id hashes the
dataset, the back-end's *resolved* options (defaults filled in from
`hamal_bench --list_backends`) and the bench flags, so "aprilsam" and
"aprilsam:delta_t=0.01" are one run.

The sweep is a JSON file (see apps/sweep/specs/*.json):

  {"datasets": {"M3500": {"data": "../shared/data/M3500.toro"},
                "gen1e4": {"generate": 10000, "seed": 1}},
   "groups": [
     {"name": "main", "datasets": ["M3500"],
      "backends": ["cholesky", "aprilsam"], "chi2_every": 1},
     {"name": "delta_t", "datasets": ["M3500"], "backends": ["aprilsam"],
      "grid": {"delta_t": [1, 0.1, 0.01]}},
     {"name": "batch", "datasets": ["gen1e4"], "backends": ["cholesky"],
      "mode": "batch"}]}

Group keys: backends (specs), grid (option -> values, cartesian product,
appended to every spec), mode (incremental | batch), chi2_every, max_steps,
reference (back-end of the batch optimum, "none" to skip), init (initial
values of batch solves: odometry, or lago for worlds whose odometry drifts
too far), timeout (s), plugin (a plugin library, or a list of them, passed
as hamal_bench --plugin: an absolute path, or one relative to the build
directory, the parent of the folder holding hamal_bench, e.g.
"plugins/libhamal_gtsam_plugin.so"; a missing one is an error before
anything runs), residual (hamal_bench --residual: thesis, the default, or
measurement, GTSAM's and g2o's). plugin and residual may also be given once
for the whole spec, at its top level.
Dataset keys: data (path, relative to the spec file) and format, or
generate (poses) and seed; chi2_every as a default for its groups.

  hamal_sweep.py SPEC.json --results DIR [--bench PATH] [--jobs N]
  hamal_sweep.py --datasets M3500=../shared/data/M3500.toro \\
      --backend "cholesky;aprilsam" --grid aprilsam:delta_t=1,0.1 --results DIR
"""

import argparse
import concurrent.futures
import datetime
import hashlib
import itertools
import json
import os
import platform
import re
import shutil
import signal
import socket
import subprocess
import sys
import threading
import time

import atomic_json
import resumable_results
import slurm_executor

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "common"))
from old_spellings import old_spelling  # noqa: E402

SCHEMA = 1  # bump when the meaning of a run changes; part of the run id

# ---------------------------------------------------------------------------
# The sweep specification and its expansion into runs.


def load_spec(path):
    with open(path) as f:
        spec = json.load(f)
    base = os.path.dirname(os.path.abspath(path))
    # Relative data paths are read from "data_dir" (relative to the spec file),
    # or from $HAMAL_DATA_DIR when it is set, as the tests do.
    data_dir = os.environ.get("HAMAL_DATA_DIR") or os.path.join(base, spec.get("data_dir", "."))
    for name, d in spec.get("datasets", {}).items():
        if "data" in d and not os.path.isabs(d["data"]):
            d["data"] = os.path.normpath(os.path.join(data_dir, d["data"]))
    return spec


def spec_from_args(args):
    """A one-group sweep from the command line (--datasets, --backend, --grid)."""
    datasets = {}
    for item in args.datasets or []:
        name, _, value = item.partition("=")
        if not value:
            raise SystemExit("hamal_sweep: --datasets wants NAME=FILE or NAME=gen:POSES[:SEED]")
        if value.startswith("gen:"):
            parts = value.split(":")
            datasets[name] = {"generate": int(parts[1]), "seed": int(parts[2]) if len(parts) > 2 else 1}
        else:
            datasets[name] = {"data": os.path.abspath(value)}
    groups = []
    if args.backends:
        groups.append({"name": "main", "datasets": list(datasets),
                       "backends": split_specs(args.backends)})
    for item in args.grid or []:
        backend, _, rest = item.partition(":")
        key, _, values = rest.partition("=")
        if not values:
            raise SystemExit("hamal_sweep: --grid wants BACKEND:OPTION=v1,v2,...")
        groups.append({"name": key, "datasets": list(datasets), "backends": [backend],
                       "grid": {key: [parse_value(v) for v in values.split(",")]}})
    for g in groups:
        if getattr(args, "plugin", None):
            g["plugin"] = list(args.plugin)
        if getattr(args, "residual", None):
            g["residual"] = args.residual
        if args.chi2_every is not None:
            g["chi2_every"] = args.chi2_every
        if args.mode:
            g["mode"] = args.mode
    return {"datasets": datasets, "groups": groups}


def parse_value(text):
    for cast in (int, float):
        try:
            return cast(text)
        except ValueError:
            pass
    return text


def split_specs(text):
    return [s.strip() for s in text.split(";") if s.strip()]


def format_value(v):
    if isinstance(v, float):
        return repr(v) if v != int(v) or abs(v) >= 1e16 else repr(v)
    return str(v)


def with_options(spec, options):
    """'aprilsam' + {'delta_t': 0.1} -> 'aprilsam:delta_t=0.1'."""
    if not options:
        return spec
    extra = ",".join(f"{k}={format_value(v)}" for k, v in options.items())
    return spec + ("," if ":" in spec else ":") + extra


def parse_backend_spec(spec):
    name, _, opts = spec.partition(":")
    options = {}
    for item in filter(None, (o.strip() for o in opts.split(","))):
        key, eq, value = item.partition("=")
        if not eq:
            raise ValueError(f"back-end spec '{spec}': option '{item}' has no '='")
        options[key.strip()] = value.strip()
    return name.strip(), options


def expand(spec):
    """The runs of a sweep: one dict per (group, dataset, back-end spec, grid point)."""
    datasets = spec.get("datasets", {})
    runs = []
    for group in spec.get("groups", []):
        gname = group.get("name", "main")
        plugins = group.get("plugin", spec.get("plugin", []))
        plugins = [plugins] if isinstance(plugins, str) else list(plugins)
        grid = group.get("grid", {})
        keys = list(grid)
        points = [dict(zip(keys, combo)) for combo in itertools.product(*(grid[k] for k in keys))]
        for dname in group.get("datasets", list(datasets)):
            if dname not in datasets:
                raise ValueError(f"group '{gname}': unknown dataset '{dname}'")
            d = datasets[dname]
            for backend in group.get("backends", []):
                for point in points:
                    runs.append({
                        "group": gname,
                        "dataset": dname,
                        "dataset_def": d,
                        "spec": with_options(backend, point),
                        "base_spec": backend,
                        "params": point,
                        "mode": group.get("mode", "incremental"),
                        "chi2_every": group.get("chi2_every", d.get("chi2_every", 1)),
                        "max_steps": group.get("max_steps", d.get("max_steps", 0)),
                        "reference": group.get("reference", d.get("reference", "cholesky")),
                        "init": group.get("init", d.get("init", "odometry")),
                        "timeout": group.get("timeout", None),
                        "plugins": plugins,
                        "residual": group.get("residual", spec.get("residual", "thesis")),
                    })
    return runs


# ---------------------------------------------------------------------------
# Resolved options: hamal_bench --list_backends lists every option's default.


def backend_defaults(bench, plugins=()):
    """Every back-end's options with their defaults, the plugins' back-ends included."""
    cmd = [bench] + [a for p in plugins for a in ("--plugin", p)] + ["--list_backends"]
    try:
        out = subprocess.run(cmd, capture_output=True, text=True, check=True).stdout
    except (OSError, subprocess.CalledProcessError):
        return {}
    defaults, current = {}, None
    for line in out.splitlines():
        if line and not line.startswith(" "):
            current = line.strip()
            defaults[current] = {}
        elif current and line.startswith("    "):
            m = re.match(r"\s+(\S+?)=(\S*)\s", line + " ")
            if m:
                defaults[current][m.group(1)] = m.group(2)
    return defaults


def resolve(spec, defaults):
    name, options = parse_backend_spec(spec)
    resolved = dict(defaults.get(name, {}))
    resolved.update(options)
    return name, resolved


def canonical_number(text):
    try:
        return repr(float(text))
    except ValueError:
        return text


def display_number(text):
    """'1.0' -> '1', '0.0001' -> '0.0001', 'amd' -> 'amd': one spelling per value."""
    try:
        f = float(text)
    except ValueError:
        return text
    return str(int(f)) if f.is_integer() and abs(f) < 1e15 else repr(f)


def run_id(run, defaults):
    """Stable name of a run: readable prefix + hash of everything that changes its numbers."""
    name, resolved = resolve(run["spec"], defaults)
    d = run["dataset_def"]
    identity = {
        "schema": SCHEMA,
        "dataset": {k: d[k] for k in ("data", "format", "generate", "seed") if k in d},
        "backend": name,
        "options": {k: canonical_number(v) for k, v in sorted(resolved.items())},
        "mode": run["mode"],
        "chi2_every": run["chi2_every"] if run["mode"] == "incremental" else 0,
        "max_steps": run["max_steps"],
        "reference": run["reference"],
    }
    init = run.get("init", "odometry")
    if init != "odometry":  # absent otherwise: earlier runs keep their ids
        identity["init"] = init
    residual = run.get("residual", "thesis")
    if residual != "thesis":  # likewise
        identity["residual"] = residual
    digest = hashlib.sha1(json.dumps(identity, sort_keys=True).encode()).hexdigest()[:10]
    # Named by the options that differ from the defaults, so that two specs
    # resolving to the same options are one directory.
    default = {k: canonical_number(v) for k, v in defaults.get(name, {}).items()}
    label = name + "".join(f"_{k}={display_number(v)}" for k, v in sorted(resolved.items())
                           if canonical_number(v) != default.get(k))
    if run["mode"] != "incremental":
        label += "_" + run["mode"]
    if init != "odometry":
        label += "_from_" + init
    if residual != "thesis":
        label += "_" + residual
    label = re.sub(r"[^A-Za-z0-9_.=+-]", "_", label)[:80]
    return f"{label}-{digest}", resolved, identity


# ---------------------------------------------------------------------------
# The machine and the source, recorded beside every run.


def git_revision(repo):
    try:
        return subprocess.run(["git", "-C", repo, "describe", "--always", "--dirty"],
                              capture_output=True, text=True, check=True).stdout.strip()
    except (OSError, subprocess.CalledProcessError):
        return "unknown"


def machine():
    cpu = platform.processor()
    try:
        with open("/proc/cpuinfo") as f:
            for line in f:
                if line.startswith("model name"):
                    cpu = line.split(":", 1)[1].strip()
                    break
    except OSError:
        pass
    mem_kb = None
    try:
        with open("/proc/meminfo") as f:
            mem_kb = int(f.readline().split()[1])
    except (OSError, ValueError, IndexError):
        pass
    return {"hostname": socket.gethostname(), "cpu": cpu, "cores": os.cpu_count(),
            "memory_kb": mem_kb, "os": platform.platform(), "python": platform.python_version()}


# ---------------------------------------------------------------------------
# Running.


def explicit_spec(run):
    name = parse_backend_spec(run["spec"])[0]
    options = run.get("resolved") or {}
    return name + (":" + ",".join(f"{k}={v}" for k, v in options.items()) if options else "")


def binary_identity(bench):
    """The bench and the shared libraries it loads from outside the system
    (libhamal.so), by size and modification time: a rebuild between two runs
    shows here even when the git revision is the same dirty tree."""
    files = [bench]
    try:
        out = subprocess.run(["ldd", bench], capture_output=True, text=True).stdout
        files += [m.group(1) for m in re.finditer(r"=> (\S*hamal\S*) ", out)]
    except OSError:
        pass
    ident = {}
    for f in files:
        try:
            st = os.stat(f)
            ident[os.path.abspath(f)] = {
                "size": st.st_size,
                "mtime": datetime.datetime.fromtimestamp(
                    st.st_mtime, datetime.timezone.utc).isoformat(timespec="seconds")}
        except OSError:
            pass
    return ident


def bench_command(bench, run):
    d = run["dataset_def"]
    cmd = [bench]
    for plugin in plugin_paths(run, bench):
        cmd += ["--plugin", plugin]
    if "data" in d:
        cmd += ["--data", d["data"], "--format", d.get("format", "auto")]
    else:
        cmd += ["--generate", str(d["generate"]), "--seed", str(d.get("seed", 1))]
    # Every option spelled out: a default changed in the source later cannot
    # silently change what a recorded configuration means.
    cmd += ["--backend", explicit_spec(run), "--reference", run["reference"],
            "--rows", "rows.csv", "--summary", "summary.json"]
    if run["mode"] == "batch":
        cmd.append("--batch")
    else:
        cmd += ["--chi2_every", str(run["chi2_every"])]
    if run["max_steps"]:
        cmd += ["--max_steps", str(run["max_steps"])]
    if run.get("init", "odometry") != "odometry":
        cmd += ["--init", run["init"]]
    if run.get("residual", "thesis") != "thesis":
        cmd += ["--residual", run["residual"]]
    return cmd


def build_dir(bench):
    """The build directory of a bench at BUILD/apps/hamal_bench."""
    return os.path.dirname(os.path.dirname(os.path.abspath(bench)))


def plugin_paths(run, bench):
    return [p if os.path.isabs(p) else os.path.normpath(os.path.join(build_dir(bench), p))
            for p in run.get("plugins", [])]


def check_plugins(runs, bench):
    """The plugins the runs ask for, each once; a missing one stops the sweep
    here, before a run fails on it."""
    paths = []
    for run in runs:
        for path in plugin_paths(run, bench):
            if path in paths:
                continue
            if not os.path.isfile(path):
                hint = " (build it: see its README under plugins/)"
                if "gtsam" in os.path.basename(path):
                    hint = (" (the GTSAM plugin: configure with -DHAMAL_WITH_GTSAM=ON "
                            "-DGTSAM_DIR=<GTSAM prefix>/lib/cmake/GTSAM and build "
                            "hamal_gtsam_plugin, see plugins/gtsam/README.md)")
                raise SystemExit(
                    f"hamal_sweep: group '{run['group']}' asks for the plugin {path}, which is "
                    f"not built{hint}; or give --bench of a build that has it")
            paths.append(path)
    return paths


def die_with_parent():
    """In the child: killed when the sweep dies, even by SIGKILL (Linux prctl
    PR_SET_PDEATHSIG), so that no orphan bench writes into a folder being resumed."""
    try:
        import ctypes
        ctypes.CDLL(None).prctl(1, signal.SIGKILL)
    except (OSError, AttributeError):
        pass


def execute(run, results, bench, context, tag=None):
    """Runs one hamal_bench in a temporary directory; renames it when complete.
    tag names the temporary directory (the process id, or the Slurm task)."""
    final = os.path.join(results, run["dataset"], run["id"])
    tmp = os.path.join(results, run["dataset"], f".tmp-{run['id']}-{tag or os.getpid()}")
    shutil.rmtree(tmp, ignore_errors=True)
    os.makedirs(tmp)
    cmd = bench_command(bench, run)
    started = datetime.datetime.now(datetime.timezone.utc).isoformat(timespec="seconds")
    t0 = time.monotonic()
    with open(os.path.join(tmp, "log.txt"), "w") as log:
        proc = subprocess.Popen(cmd, cwd=tmp, stdout=log, stderr=subprocess.STDOUT,
                                stdin=subprocess.DEVNULL, preexec_fn=die_with_parent)
        context["procs"].add(proc)
        timer = None
        if run.get("timeout"):
            timer = threading.Timer(run["timeout"], proc.kill)
            timer.start()
        # wait4 gives the child's own rusage: its peak resident memory.
        _, status, usage = os.wait4(proc.pid, 0)
        proc.returncode = os.waitstatus_to_exitcode(status)
        if timer:
            timer.cancel()
        context["procs"].discard(proc)
    wall = time.monotonic() - t0
    config = {
        "run_id": run["id"],
        "dataset": run["dataset"],
        "dataset_def": run["dataset_def"],
        "spec": run["spec"],
        "backend": run["backend"],
        "resolved_options": run["resolved"],
        "identity": run["identity"],
        "mode": run["mode"],
        "chi2_every": run["chi2_every"],
        "max_steps": run["max_steps"],
        "reference": run["reference"],
        "init": run.get("init", "odometry"),
        "residual": run.get("residual", "thesis"),
        "plugins": plugin_paths(run, bench),
        "command": cmd,
        "git_revision": context["git"],
        "binaries": binary_identity(bench),
        "machine": context["machine"],
        "started": started,
        "wall_seconds": wall,
        "peak_rss_kb": usage.ru_maxrss,
        "user_seconds": usage.ru_utime,
        "exit_status": proc.returncode,
    }
    # How many rows the run wrote: a rows.csv cut later at a line break has
    # fewer, and is not taken as complete (verify_run).
    rows_file = os.path.join(tmp, "rows.csv")
    if proc.returncode == 0 and os.path.exists(rows_file):
        config["rows"] = resumable_results.count_rows(rows_file)
    with open(os.path.join(tmp, "config.json"), "w") as f:
        json.dump(config, f, indent=1)
    ok = proc.returncode == 0 and os.path.exists(os.path.join(tmp, "summary.json"))
    if context.get("interrupted"):
        return False, wall  # stays .tmp-*: redone next time
    if not ok:
        failed = os.path.join(results, "failed", run["dataset"], run["id"])
        shutil.rmtree(failed, ignore_errors=True)
        os.makedirs(os.path.dirname(failed), exist_ok=True)
        os.rename(tmp, failed)
        return False, wall
    os.rename(tmp, final)  # atomic: the run exists complete or not at all
    return True, wall


def fmt_duration(s):
    s = int(round(s))
    if s < 60:
        return f"{s}s"
    if s < 3600:
        return f"{s // 60}m{s % 60:02d}s"
    return f"{s // 3600}h{(s % 3600) // 60:02d}m"


class Progress:
    """A progress bar on stderr; the time left is weighted by each run's expected cost."""

    def __init__(self, weights, stream=sys.stderr):
        self.weights = weights
        self.total = sum(weights.values()) or 1
        self.done_weight = 0
        self.done = 0
        self.failed = 0
        self.running = {}
        self.start = time.monotonic()
        self.stream = stream
        self.lock = threading.Lock()
        self.tty = stream.isatty()
        self.last = 0

    def begin(self, rid):
        with self.lock:
            self.running[rid] = time.monotonic()

    def end(self, rid, ok):
        with self.lock:
            self.running.pop(rid, None)
            self.done += 1
            self.failed += 0 if ok else 1
            self.done_weight += self.weights[rid]

    def line(self):
        n = len(self.weights)
        frac = self.done_weight / self.total
        elapsed = time.monotonic() - self.start
        eta = "?"
        if self.done_weight > 0:
            eta = "~" + fmt_duration(elapsed * (self.total - self.done_weight) / self.done_weight)
        width = 30
        bar = "#" * int(width * frac) + "." * (width - int(width * frac))
        fail = f", {self.failed} failed" if self.failed else ""
        pending = n - self.done - len(self.running)
        return (f"[{bar}] {self.done}/{n} runs{fail}, {len(self.running)} running, "
                f"{pending} pending, "
                f"{fmt_duration(elapsed)} elapsed, {eta} left")

    def show(self, force=False):
        now = time.monotonic()
        if not force and not self.tty and now - self.last < 30:
            return
        self.last = now
        with self.lock:
            text = self.line()
        if self.tty:
            self.stream.write("\r" + text + "\033[K")
        else:
            self.stream.write(text + "\n")
        self.stream.flush()


def expected_cost(run):
    """A rough relative cost for the time-left estimate: poses x a per-back-end factor."""
    d = run["dataset_def"]
    if "generate" in d:
        size = d["generate"]
    else:
        try:
            size = os.path.getsize(d["data"]) / 100.0
        except OSError:
            size = 1000
    if run["max_steps"]:
        size = min(size, run["max_steps"])
    if run["mode"] == "batch":
        return size * 0.01
    factor = {"cholesky": 20, "ceres": 40, "isam2": 10}.get(run["backend"], 1)
    if run["backend"] == "ceres":
        every = int(run["resolved"].get("every", 1) or 1)
        factor = max(1, factor / every)
    if run["backend"] == "aprilsam-periodic" or run["resolved"].get("mode") == "periodic":
        period = int(float(run["resolved"].get("period", 50) or 50))
        factor *= max(1.0, 10.0 / period)
    return size * size / 1000.0 * factor


def plan(spec, results, bench, defaults):
    """Runs with ids; those already complete are marked done."""
    runs = expand(spec)
    by_id = {}
    for run in runs:
        run["id"], run["resolved"], run["identity"] = run_id(run, defaults)
        run["backend"] = parse_backend_spec(run["spec"])[0]
    for run in runs:
        by_id.setdefault((run["dataset"], run["id"]), run)
    for run in by_id.values():
        run["done"] = verify_run(results, run)
    for run in runs:
        run["done"] = by_id[(run["dataset"], run["id"])]["done"]
    return runs, list(by_id.values())


def verify_run(results, run):
    """Whether a run is done, its folder verified (resumable_results' rules): its
    config.json present and naming this run's identity, summary.json and every
    row of rows.csv whole, as many rows as config.json says the run wrote (a
    folder of before that count: all its rows). A run whose rows.csv ends in a
    torn row or lost rows, or that lacks its rows or summary, is moved to
    failed/ and redone; the rest is refused."""
    folder = os.path.join(results, run["dataset"], run["id"])
    if not os.path.isdir(folder):
        return False
    config = os.path.join(folder, "config.json")
    if not os.path.exists(config):
        raise resumable_results.ResultsError(
            f"hamal_sweep: {config}: missing beside the run's results, so nothing says which "
            "parameters made them; move the run away to redo it")
    recorded = resumable_results.read_json(config)
    there = recorded.get("identity") if isinstance(recorded, dict) else None
    reason = resumable_results.differing_parameter(there if isinstance(there, dict) else {},
                                                   run["identity"])
    if reason:
        raise resumable_results.ResultsError(
            f"hamal_sweep: {config}: this run folder holds a run of other parameters "
            f"({reason}); move it away to redo it")
    damage = None
    for name in ("summary.json", "rows.csv"):
        if not os.path.exists(os.path.join(folder, name)):
            damage = f"no {name}"
    if not damage:
        resumable_results.read_json(os.path.join(folder, "summary.json"))
        rows, torn = resumable_results.read_rows(os.path.join(folder, "rows.csv"))
        if torn:
            damage = "rows.csv ends in a torn row"
        elif isinstance(recorded.get("rows"), int) and len(rows) != recorded["rows"]:
            damage = (f"rows.csv has {len(rows)} rows, the run wrote {recorded['rows']} "
                      "(config.json)")
    if not damage:
        return True
    failed = os.path.join(results, "failed", run["dataset"], run["id"])
    shutil.rmtree(failed, ignore_errors=True)
    os.makedirs(os.path.dirname(failed), exist_ok=True)
    os.rename(folder, failed)
    print(f"hamal_sweep: {folder}: {damage}; moved to {failed}, the run is redone",
          file=sys.stderr)
    return False


def check_datasets(results, spec):
    """A results folder holds one meaning per dataset name: a spec that defines a
    name otherwise than the folder's manifest is refused, naming the parameter."""
    path = os.path.join(results, "manifest.json")
    if not os.path.exists(path):
        return
    manifest = resumable_results.read_json(path)
    known = manifest.get("datasets", {}) if isinstance(manifest, dict) else {}
    for name, definition in spec.get("datasets", {}).items():
        if name in known:
            reason = resumable_results.differing_parameter(known[name], definition,
                                                           f"datasets.{name}.")
            if reason:
                raise resumable_results.ResultsError(
                    f"hamal_sweep: {path}: this folder holds results of another spec "
                    f"({reason}); use another --results")


def write_manifest(results, spec, runs):
    """Which run belongs to which group and value: what hamal_report reads.

    Entries of earlier sweeps into the same folder are kept (keyed by group,
    dataset and spec), so several sweeps can share one results folder."""
    path = os.path.join(results, "manifest.json")
    manifest = {"datasets": {}, "entries": []}
    if os.path.exists(path):
        with open(path) as f:
            manifest = json.load(f)
    manifest["datasets"].update(spec.get("datasets", {}))
    entries = {(e["group"], e["dataset"], e["spec"], e.get("mode", "incremental")): e
               for e in manifest["entries"]}
    for run in runs:
        entries[(run["group"], run["dataset"], run["spec"], run["mode"])] = {
            "group": run["group"], "dataset": run["dataset"], "spec": run["spec"],
            "base_spec": run["base_spec"], "backend": run["backend"], "params": run["params"],
            "mode": run["mode"], "run_id": run["id"]}
    manifest["entries"] = list(entries.values())
    atomic_json.write_json(path, manifest)


def sweep(spec, results, bench, jobs, dry_run=False, quiet=False, revision=None,
          executor="local", slurm=None, locked=False):
    """slurm: the Slurm executor's options (partition, time, mem, cpus_per_task,
    account, sbatch_args, max_parallel, poll). locked: the caller holds the
    folder's lock (resumable_results.lock) already, taken before it wrote there."""
    if executor not in ("local", "slurm"):
        raise SystemExit(f"hamal_sweep: unknown executor '{executor}' (local or slurm)")
    if executor == "slurm" and not dry_run:
        slurm_executor.require_tools()
    plugins = check_plugins(expand(spec), bench)
    os.makedirs(results, exist_ok=True)
    if not locked:
        lock = resumable_results.lock(results, "hamal_sweep: another sweep")  # noqa: F841
    record = slurm_executor.load_record(results)
    if executor != "slurm":
        slurm_executor.refuse_local_beside_jobs(results)
    check_datasets(results, spec)
    if executor == "slurm" and not dry_run:
        return sweep_on_slurm(spec, results, bench, plugins, record, quiet, revision, slurm or {})
    remove_half_written(results)  # of an interrupted sweep: redone below
    defaults = backend_defaults(bench, plugins)
    if not defaults:
        raise SystemExit(f"hamal_sweep: cannot run {bench} --list_backends")
    runs, unique = plan(spec, results, bench, defaults)
    write_manifest(results, spec, runs)
    todo = [r for r in unique if not r["done"]]
    print(f"hamal_sweep: {len(unique)} runs, {len(unique) - len(todo)} already done, "
          f"{len(todo)} to run on {jobs} workers -> {results}", file=sys.stderr)
    if dry_run:
        for r in todo:
            print(" ".join(bench_command(bench, r)), file=sys.stderr)
        return 0
    if not todo:
        return 0
    for r in todo:
        os.makedirs(os.path.join(results, r["dataset"]), exist_ok=True)
    context = {"git": revision or git_revision(os.path.dirname(os.path.abspath(__file__))),
               "machine": machine(), "procs": set()}
    # Longest first, so that the pool does not end on one long run.
    todo.sort(key=expected_cost, reverse=True)
    progress = Progress({r["id"]: expected_cost(r) for r in todo},
                        stream=open(os.devnull, "w") if quiet else sys.stderr)
    failures = []

    def job(run):
        progress.begin(run["id"])
        ok, wall = execute(run, results, bench, context)
        progress.end(run["id"], ok)
        if not ok:
            failures.append(run)
        return ok

    # SIGTERM as Ctrl-C: the running benches are killed, their half-written
    # directories stay as .tmp-* and are redone by the next sweep.
    def terminate(signum, frame):
        raise KeyboardInterrupt
    signal.signal(signal.SIGTERM, terminate)
    pool = concurrent.futures.ThreadPoolExecutor(max_workers=jobs)
    try:
        futures = [pool.submit(job, r) for r in todo]
        while not all(f.done() for f in futures):
            progress.show()
            time.sleep(1)
        for f in futures:
            f.result()
    except KeyboardInterrupt:
        context["interrupted"] = True
        pool.shutdown(wait=False, cancel_futures=True)
        for proc in list(context["procs"]):
            proc.kill()
        print("\nhamal_sweep: interrupted; finished runs are kept, run again to resume",
              file=sys.stderr)
        return 130
    pool.shutdown()
    progress.show(force=True)
    if not quiet:
        sys.stderr.write("\n")
    for r in failures:
        log = os.path.join(results, "failed", r["dataset"], r["id"], "log.txt")
        reason = last_error(log)
        print(f"hamal_sweep: FAILED {r['dataset']}/{r['id']} ({r['spec']}): "
              f"{reason + '; ' if reason else ''}see {log}", file=sys.stderr)
    return 1 if failures else 0


def last_error(log):
    """The tool's own error line in a failed run's log ("...: error: ..."), or ''.

    A run that failed for its surroundings (a full disk, a read-only folder)
    says so there; the sweep's line repeats it so that the reason is seen
    without opening every log."""
    try:
        with open(log, errors="replace") as f:
            lines = [line.strip() for line in f if ": error:" in line]
    except OSError:
        return ""
    return lines[-1] if lines else ""


def remove_half_written(results):
    """Temporary directories of runs that were interrupted: redone."""
    for dname in os.listdir(results):
        ddir = os.path.join(results, dname)
        if os.path.isdir(ddir):
            for entry in os.listdir(ddir):
                if entry.startswith(".tmp-"):
                    shutil.rmtree(os.path.join(ddir, entry), ignore_errors=True)


def sweep_on_slurm(spec, results, bench, plugins, record, quiet, revision, options):
    """The runs not yet done as Slurm array jobs, watched to the end; attaches to
    the jobs recorded by an earlier invocation instead of submitting them again."""
    if not record:
        slurm_executor.refuse_unrecorded_jobs(results)
        remove_half_written(results)
    defaults = backend_defaults(bench, plugins)
    if not defaults:
        raise SystemExit(f"hamal_sweep: cannot run {bench} --list_backends")
    runs, unique = plan(spec, results, bench, defaults)
    write_manifest(results, spec, runs)
    git = revision or git_revision(os.path.dirname(os.path.abspath(__file__)))
    tasks = []
    for r in sorted(unique, key=expected_cost, reverse=True):
        os.makedirs(os.path.join(results, r["dataset"]), exist_ok=True)
        tasks.append(dict(r, git=git, label=f"{r['dataset']}/{r['id']} ({r['spec']})",
                          done=os.path.join(results, r["dataset"], r["id"]),
                          failed=os.path.join(results, "failed", r["dataset"], r["id"]),
                          tmp=os.path.join(results, r["dataset"], f".tmp-{r['id']}-{{task}}")))
    here = os.path.abspath(__file__)
    return slurm_executor.run_tasks(
        tasks, results, [here, "--results", results, "--bench", bench, "--slurm_task"], options,
        Progress, quiet=quiet, cost=expected_cost)


def run_slurm_task(tasks, results, bench):
    """Inside an array task: line $SLURM_ARRAY_TASK_ID of the tasks file, run once."""
    run, tag = slurm_executor.task_line(tasks)
    if os.path.isdir(os.path.join(results, run["dataset"], run["id"])):
        print(f"hamal_sweep: {run['dataset']}/{run['id']} is already done", file=sys.stderr)
        return 0
    context = {"git": run.get("git", "unknown"), "machine": machine(), "procs": set()}
    ok, wall = execute(run, results, bench, context, tag=tag)
    print(f"hamal_sweep: {run['dataset']}/{run['id']} {'done' if ok else 'FAILED'} "
          f"in {wall:.1f}s", file=sys.stderr)
    return 0 if ok else 1


def default_bench():
    here = os.path.dirname(os.path.abspath(__file__))
    for candidate in (os.environ.get("HAMAL_BENCH"),
                      os.path.join(here, "..", "..", "build", "apps", "hamal_bench")):
        if candidate and os.path.exists(candidate):
            return os.path.abspath(candidate)
    return shutil.which("hamal_bench") or "hamal_bench"


def split_passthrough(argv):
    """(the runner's own arguments, those after a `--`): a runner hands the
    latter to the executable it runs, unparsed."""
    if "--" not in argv:
        return list(argv), []
    k = argv.index("--")
    return argv[:k], argv[k + 1:]


def add_executor_arguments(p):
    """--executor and the Slurm executor's options, for every runner built on the sweep."""
    p.add_argument("--executor", default="local",
                   help="local (processes here, --jobs at once) or slurm (an sbatch --array "
                        "job, watched; see docs/EXPERIMENTS.md)")
    s = p.add_argument_group("Slurm executor (--executor slurm)")
    s.add_argument("--partition", help="sbatch --partition")
    s.add_argument("--time", help="sbatch --time, per run (e.g. 0:30:00)")
    s.add_argument("--mem", help="sbatch --mem, per run (e.g. 4G)")
    s.add_argument("--cpus_per_task", "--cpus-per-task", dest="cpus_per_task",
                   help="sbatch --cpus-per-task")
    s.add_argument("--account", help="sbatch --account")
    s.add_argument("--sbatch_args", default="",
                   help="further sbatch arguments, one shell-quoted string")
    s.add_argument("--max_parallel", "--max-parallel", dest="max_parallel", type=int,
                   default=None, help="array tasks at once (the array's %% throttle)")
    s.add_argument("--poll", type=float, default=10, help="seconds between squeue polls")


def executor_options(args):
    """The Slurm executor's options of parsed arguments (see add_executor_arguments)."""
    if args.executor not in ("local", "slurm"):
        raise SystemExit(f"hamal_sweep: unknown --executor '{args.executor}': local or slurm")
    return {k: getattr(args, k) for k in ("partition", "time", "mem", "cpus_per_task", "account",
                                          "sbatch_args", "max_parallel", "poll")}


def main(argv=None):
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0],
                                formatter_class=argparse.RawDescriptionHelpFormatter,
                                epilog=__doc__.split("\n\n", 1)[1])
    p.add_argument("spec", nargs="?", help="sweep JSON file")
    p.add_argument("--results", required=True, help="results folder (created; resumed)")
    p.add_argument("--bench", default=None, help="hamal_bench (default: $HAMAL_BENCH, build/apps)")
    p.add_argument("--jobs", type=int, default=os.cpu_count() or 1,
                   help="runs in parallel (default: the cores)")
    p.add_argument("--datasets", action="append", help="NAME=FILE or NAME=gen:POSES[:SEED]")
    p.add_argument("--backend", dest="backends", help="back-end specs separated by ';'")
    old_spelling(p, "--backends", "--backend")
    p.add_argument("--grid", action="append", help="BACKEND:OPTION=v1,v2,... (a swept group)")
    p.add_argument("--chi2_every", type=int, default=None)
    p.add_argument("--mode", choices=["incremental", "batch"], default=None)
    p.add_argument("--plugin", action="append",
                   help="plugin library of a command-line sweep (repeatable; see 'plugin')")
    p.add_argument("--residual", choices=["thesis", "measurement"], default=None,
                   help="between residual of a command-line sweep (default: thesis)")
    p.add_argument("--only", action="append",
                   help="run only these groups of the spec (repeatable)")
    p.add_argument("--only_datasets", action="append",
                   help="run only these datasets of the spec (repeatable, or comma separated)")
    p.add_argument("--git_revision", default=None,
                   help="the revision the bench was built from, when it is not this tree's "
                        "(default: git describe --always --dirty here)")
    p.add_argument("--dry_run", action="store_true", help="print what would run")
    add_executor_arguments(p)
    p.add_argument("--slurm_task", help=argparse.SUPPRESS)
    p.add_argument("--quiet", action="store_true", help="no progress bar")
    args = p.parse_args(argv)
    bench = os.path.abspath(args.bench) if args.bench else default_bench()
    if args.slurm_task:
        return run_slurm_task(args.slurm_task, os.path.abspath(args.results), bench)
    slurm = executor_options(args)
    spec = load_spec(args.spec) if args.spec else spec_from_args(args)
    if args.only:
        spec["groups"] = [g for g in spec["groups"] if g.get("name") in args.only]
    if args.only_datasets:
        keep = {d for item in args.only_datasets for d in item.split(",")}
        unknown = keep - set(spec.get("datasets", {}))
        if unknown:
            raise SystemExit(f"hamal_sweep: no dataset {', '.join(sorted(unknown))} in the spec")
        for g in spec["groups"]:
            g["datasets"] = [d for d in g.get("datasets", list(spec["datasets"])) if d in keep]
    return sweep(spec, os.path.abspath(args.results), bench, max(1, args.jobs),
                 dry_run=args.dry_run, quiet=args.quiet, revision=args.git_revision,
                 executor=args.executor, slurm=slurm)


if __name__ == "__main__":
    sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "common"))
    import script_errors  # noqa: E402
    sys.exit(script_errors.run("hamal_sweep", main))
