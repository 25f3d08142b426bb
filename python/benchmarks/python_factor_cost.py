#!/usr/bin/env python3
"""The cost of a factor written in Python (python/README.md, "Cost").

A 1000-pose world (a square loop, odometry and a loop closure every 25
poses) is solved under the thesis protocol twice by one back-end: with the
C++ between factor, and with its twin written in Python
(python/examples/python_between.py). The callable counts its calls, so
  cost per evaluation = (time with Python factors - time with C++ ones) / calls
in microseconds, GIL, numpy arrays in and out and the checks included; then
that cost split into the callable itself and hamal's crossing into Python.

    PYTHONPATH=build/python python3 python/benchmarks/python_factor_cost.py --backend aprilsam
"""

import argparse
import math
import os
import sys
import time

import numpy as np

import hamal
from hamal import x

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "examples"))
from python_between import between as python_between, between_function  # noqa: E402


def world(poses=1000, seed=2):
    rng = np.random.default_rng(seed)
    info = np.diag([100.0, 100.0, 400.0])
    truth = [hamal.Pose2()]
    for i in range(1, poses):
        truth.append(truth[-1].compose(hamal.Pose2(1.0, 0.0, math.pi / 2 if i % 10 == 0 else 0.0)))
    edges = [(i - 1, i) for i in range(1, poses)] + [(i - 25, i) for i in range(25, poses, 25)]
    return [(a, b, truth[a].between(truth[b]).vector() + rng.normal(0, [0.05, 0.05, 0.01]), info)
            for a, b in edges]


def timed(edges, spec, python):
    counter = [0]
    g = hamal.Graph()
    for a, b, z, info in edges:
        g.add(python_between(x(a), x(b), z, info, counter) if python else hamal.between(x(a), x(b), z, info))
    start = time.perf_counter()
    run = hamal.run(g, spec)
    return time.perf_counter() - start, counter[0], run


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--backend", default="aprilsam")
    parser.add_argument("--poses", type=int, default=1000)
    args = parser.parse_args()
    edges = world(args.poses)
    t_cpp, _, cpp = timed(edges, args.backend, python=False)
    t_py, calls, py = timed(edges, args.backend, python=True)
    print(f"{args.poses} poses, {len(edges)} between factors, {args.backend}, thesis protocol")
    print(f"C++ factors:    {t_cpp:.3f} s, chi2 {cpp.chi2:.6f}")
    print(f"Python factors: {t_py:.3f} s, chi2 {py.chi2:.6f}, {calls} evaluations "
          f"({calls / len(py.results):.1f} per step)")
    print(f"cost per evaluation of the Python factor: {1e6 * (t_py - t_cpp) / calls:.1f} us")
    # The same evaluation three ways, at one state: the callable called from
    # Python, the Python factor through hamal (Factor.linearize: C++ ->
    # Python -> C++), and the C++ twin through the same binding.
    a, b, z, info = edges[0]
    f = between_function(z, info)
    py_factor, cpp_factor = python_between(x(0), x(1), z, info), hamal.between(x(0), x(1), z, info)
    params = [np.array([0.1, 0.2, 0.3]), np.array([1.0, 0.1, 0.35])]
    values = hamal.Values.from_numpy(np.array(params))
    n = 10000

    def per_call(fn):  # the fastest of 5 rounds: the least disturbed by other load
        rounds = []
        for _ in range(5):
            start = time.perf_counter()
            for _ in range(n):
                fn()
            rounds.append(1e6 * (time.perf_counter() - start) / n)
        return min(rounds)

    direct = per_call(lambda: f(params))
    through = per_call(lambda: py_factor.linearize(values))
    twin = per_call(lambda: cpp_factor.linearize(values))
    print(f"  the callable alone (numpy, called from Python):  {direct:.1f} us")
    print(f"  hamal's crossing (GIL, arrays in and out, checks): {through - twin - direct:.1f} us")

if __name__ == "__main__":
    main()
