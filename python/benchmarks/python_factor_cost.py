#!/usr/bin/env python3
"""The cost of a factor written in Python (python/README.md, "Cost").

A 1000-pose world (a square loop, odometry and a loop closure every 25
poses) is solved under the thesis protocol twice by one back-end: with the
C++ between factor, and with its twin written in Python (the thesis residual
and Jacobians in numpy, as in python/tests/test_python_factor.py). The
callable counts its calls, so
  cost per evaluation = (time with Python factors - time with C++ ones) / calls
in microseconds, GIL, numpy arrays in and out and the checks included.

    PYTHONPATH=build/python python3 python/benchmarks/python_factor_cost.py --backend aprilsam
"""

import argparse
import math
import time

import numpy as np

import hamal
from hamal import x


def between_function(z, information, counter):
    u = np.linalg.cholesky(information).T
    z = np.asarray(z, dtype=float)

    def f(params):
        counter[0] += 1
        pa, pb = params
        c, s = math.cos(pa[2]), math.sin(pa[2])
        rt = np.array([[c, s], [-s, c]])
        d = pb[:2] - pa[:2]
        e = np.empty(3)
        e[:2] = rt @ d - z[:2]
        e[2] = hamal.wrap_angle(pb[2] - pa[2] - z[2])
        ja = np.zeros((3, 3))
        ja[:2, :2] = -rt
        ja[:2, 2] = np.array([[-s, c], [-c, -s]]) @ d
        ja[2, 2] = -1
        jb = np.zeros((3, 3))
        jb[:2, :2] = rt
        jb[2, 2] = 1
        return u @ e, [u @ ja, u @ jb]

    return f


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
        g.add(hamal.PythonFactor([x(a), x(b)], 3, between_function(z, info, counter)) if python
              else hamal.between(x(a), x(b), z, info))
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


if __name__ == "__main__":
    main()
