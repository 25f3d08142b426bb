#!/usr/bin/env python3
"""What a Python loop adds to a back-end's update time (python/README.md, "Cost").

Runs hamal_bench's C++ loop and the same loop in Python (hamal.run: the
thesis protocol's steps made in C++ from the back-end's estimate, one
backend.update per step) on one dataset, in turns, and prints
  - hamal_bench's cumulative update time (median over its repeats),
  - the Python loop's wall time, everything included (steps made, results
    returned), and the sum of its update calls,
  - overhead = Python wall time / hamal_bench's update time - 1,
  - the loop's own part, (wall - its update calls) per step, which the
    machine's load moves far less than the two update times.
hamal_bench times only the update calls, so the overhead counts making the
steps as well as the Python calls. A benchmark, not a test: the figure moves
with the machine's load; run it on a quiet machine.

    PYTHONPATH=build/python python3 python/benchmarks/loop_overhead.py \
        --bench build/apps/hamal_bench --backend aprilsam --turns 3
"""

import argparse
import json
import os
import statistics
import subprocess
import tempfile

import hamal


def bench_seconds(bench, data, spec):
    with tempfile.TemporaryDirectory() as tmp:
        summary = os.path.join(tmp, "summary.json")
        subprocess.run([bench, "--data", data, "--backend", spec, "--chi2_every", "0",
                        "--reference", "none", "--summary", summary], check=True, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
        with open(summary) as f:
            return json.load(f)[0]["cumulative_seconds"]


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--bench", default="build/apps/hamal_bench")
    parser.add_argument("--data", default=None, help="default: M3500.toro in the data directory")
    parser.add_argument("--backend", default="aprilsam")
    parser.add_argument("--turns", type=int, default=3)
    args = parser.parse_args()
    data = args.data or hamal.dataset("M3500.toro")
    graph = hamal.read_graph(data)
    cpp, wall, updates = [], [], []
    for _ in range(args.turns):
        cpp.append(bench_seconds(args.bench, data, args.backend))
        run = hamal.run(graph, args.backend)
        wall.append(run.wall_seconds)
        updates.append(run.seconds.sum())
    c, w, u = statistics.median(cpp), statistics.median(wall), statistics.median(updates)
    print(f"{os.path.basename(data)}, {args.backend}, {len(run.results)} steps, median of {args.turns} turns")
    print(f"hamal_bench update time:     {c:.3f} s")
    print(f"Python loop, wall:           {w:.3f} s  (its update calls: {u:.3f} s)")
    print(f"overhead of the Python loop: {100 * (w / c - 1):.1f} % of hamal_bench's update time")
    print(f"the loop's own part (wall - its update calls): {1e6 * (w - u) / len(run.results):.1f} us per step")


if __name__ == "__main__":
    main()
