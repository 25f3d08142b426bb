#!/usr/bin/env python3
"""What the last pose's marginal covariance costs (python/README.md,
"Marginal covariances"), per back-end, on one dataset (city10000 by default).

cholesky gets the whole graph as one batch step (the thesis protocol's
batch(): odometry guesses and the prior); every other back-end gets the same
step started from cholesky's optimum, so that AprilSAM, whose covariance is
at its linearisation points (its batch's starting values), is compared at the
same point. Then the last pose's 3 x 3 covariance and the joint of the last
and first poses are asked `--repeats` times; the median of each is printed,
with the batch's time for scale (the others' batch starts at the optimum),
and the largest difference of the last pose's covariance from cholesky's
(relative to its largest entry). A benchmark, not a test: the figures move
with the machine's load.

    PYTHONPATH=build/python python3 python/benchmarks/marginals_cost.py \
        --data city10000.g2o --backends cholesky,ceres,aprilsam,aprilsam-top

With `--gtsam HARNESS` (plugins/gtsam's hamal_gtsam_marginals), GTSAM's
Marginals is asked for the same covariance in the same run: cholesky's
optimum is written as a g2o file of values (17 digits), the harness
linearises there (the same prior, GTSAM's residual, so `--residual`
defaults to measurement) and its median construction and query times over
`--repeats` are printed beside hamal's, with each back-end's largest
absolute and relative (to GTSAM's largest entry) difference from GTSAM's
covariance, rotated into hamal's world-frame tangent (core/marginals.h).
"""

import argparse
import json
import os
import statistics
import subprocess
import tempfile
import time

import numpy as np

import hamal


def timed(f, repeats):
    seconds, out = [], None
    for _ in range(repeats):
        start = time.perf_counter()
        out = f()
        seconds.append(time.perf_counter() - start)
    return statistics.median(seconds), out


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--data", default="city10000.g2o", help="a dataset name or path")
    parser.add_argument("--backends", default="cholesky,ceres,aprilsam,aprilsam-top")
    parser.add_argument("--repeats", type=int, default=5)
    parser.add_argument("--gtsam", metavar="HARNESS",
                        help="hamal_gtsam_marginals, to compare with GTSAM's Marginals")
    parser.add_argument("--residual", choices=["thesis", "measurement"],
                        help="the between residual (default: measurement with --gtsam, "
                             "GTSAM's; thesis without)")
    args = parser.parse_args()
    residual = args.residual or ("measurement" if args.gtsam else "thesis")
    if args.gtsam and residual != "measurement":
        parser.error("--gtsam needs --residual measurement, GTSAM's BetweenFactor residual")

    path = hamal.dataset(args.data) if not os.path.isfile(args.data) else args.data
    graph = hamal.read_graph(path)
    hamal.set_between_residual(graph, residual)
    protocol = hamal.ThesisProtocol(graph)
    batch = protocol.batch()
    first, last = protocol.pose(0), protocol.pose(len(protocol) - 1)
    print(f"{args.data}: {len(batch.new_values)} variables, {len(batch.new_factors)} factors; "
          f"covariance of {last}, joint with {first}; median of {args.repeats}")
    optimum = hamal.backend("cholesky")
    if not optimum.update(batch).status.ok:
        raise SystemExit("cholesky's batch failed: no optimum to start from")
    at_optimum = hamal.Step(0, optimum.estimate(), list(batch.new_factors), list(batch.fixed))
    gtsam = run_gtsam(args.gtsam, path, optimum.estimate(), args.repeats) if args.gtsam else None
    print(f"{'backend':>14} {'batch s':>9} {'last pose s':>12} {'joint s':>9} {'vs cholesky':>12}"
          + (f" {'vs GTSAM abs':>13} {'rel':>8}" if gtsam else ""))
    if gtsam:
        print(f"{'GTSAM ' + gtsam['gtsam_version']:>14} {'-':>9} "
              f"{gtsam['construct_seconds'] + gtsam['query_seconds']:12.2e} {'-':>9} "
              f"(Marginals {gtsam['construct_seconds']:.2e} s + "
              f"query {gtsam['query_seconds']:.2e} s)")
    covariances = {}
    reference = None
    for spec in args.backends.split(","):
        b = hamal.backend(spec)
        start = time.perf_counter()
        status = b.update(batch if spec == "cholesky" else at_optimum).status
        batch_seconds = time.perf_counter() - start
        if not status.ok:
            print(f"{spec:>14} update failed: {status.message}")
            continue
        one_seconds, one = timed(lambda: b.marginal_covariance(last), args.repeats)
        joint_seconds, _ = timed(lambda: b.joint_marginal_covariance([last, first]), args.repeats)
        if reference is None and spec == "cholesky":
            reference = one
        diff = (f"{np.abs(one - reference).max() / np.abs(reference).max():.1e}"
                if reference is not None else "-")
        vs_gtsam = ""
        if gtsam:
            reference_gtsam = gtsam["covariance"]
            gap = np.abs(one - reference_gtsam).max()
            vs_gtsam = f" {gap:13.1e} {gap / np.abs(reference_gtsam).max():8.1e}"
        covariances[spec] = one
        print(f"{spec:>14} {batch_seconds:9.3f} {one_seconds:12.2e} {joint_seconds:9.2e} {diff:>12}"
              + vs_gtsam)
    if gtsam:
        covariances["GTSAM"] = gtsam["covariance"]
        print(f"\ncovariance of {last} (x, y world frame; theta):")
        with np.printoptions(precision=12, suppress=False, linewidth=120):
            for name, c in covariances.items():
                print(f"{name}:\n{c}")


def run_gtsam(harness, path, values, repeats):
    """GTSAM's Marginals of the last pose at `values` (hamal_gtsam_marginals)."""
    with tempfile.TemporaryDirectory() as directory:
        at = os.path.join(directory, "values.g2o")
        hamal.write_g2o(at, values, [])
        out = subprocess.run([harness, "--data", path, "--values", at, "--repeat", str(repeats)],
                             check=True, capture_output=True, text=True).stdout
    result = json.loads(out)
    result["covariance"] = np.array(result["covariance_world"])
    return result


if __name__ == "__main__":
    main()
