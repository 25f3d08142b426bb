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
"""

import argparse
import statistics
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
    args = parser.parse_args()

    protocol = hamal.ThesisProtocol(hamal.read_graph(hamal.dataset(args.data)))
    batch = protocol.batch()
    first, last = protocol.pose(0), protocol.pose(len(protocol) - 1)
    print(f"{args.data}: {len(batch.new_values)} variables, {len(batch.new_factors)} factors; "
          f"covariance of {last}, joint with {first}; median of {args.repeats}")
    print(f"{'backend':>14} {'batch s':>9} {'last pose s':>12} {'joint s':>9} {'vs cholesky':>12}")
    optimum = hamal.backend("cholesky")
    if not optimum.update(batch).status.ok:
        raise SystemExit("cholesky's batch failed: no optimum to start from")
    at_optimum = hamal.Step(0, optimum.estimate(), list(batch.new_factors), list(batch.fixed))
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
        print(f"{spec:>14} {batch_seconds:9.3f} {one_seconds:12.2e} {joint_seconds:9.2e} {diff:>12}")


if __name__ == "__main__":
    main()
