#!/usr/bin/env python3
"""A factor written in Python, solved by aprilsam: range-only beacons.

A robot drives a loop among four radio beacons whose positions a survey
gives to within about 2 m (a landmark prior). Each pose measures its distance to the beacons in
range; hamal has no range-only factor, so it is written here in Python,
r = sqrt(w) (|b - t| - z), with its Jacobians, checked with
hamal.check_jacobians, and used by aprilsam next to the C++ odometry factors.

    PYTHONPATH=build/python python3 python/examples/range_only_factor.py
"""

import math

import numpy as np

import hamal
from hamal import l, x


def range_only(pose, beacon, distance, sigma):
    """A hamal.PythonFactor: the distance from pose `pose` to landmark `beacon`."""
    w = 1.0 / sigma

    def residual(params):
        p, b = params
        d = b - p[:2]
        n = math.hypot(d[0], d[1])
        u = d / n
        return (np.array([w * (n - distance)]),
                [np.array([[-w * u[0], -w * u[1], 0.0]]), np.array([[w * u[0], w * u[1]]])])

    return hamal.PythonFactor([pose, beacon], 1, residual, name=f"range_only({pose}, {beacon})")


def simulate(poses=300, seed=5):
    """Truth, odometry and ranges of a loop among four beacons."""
    rng = np.random.default_rng(seed)
    beacons = np.array([[0.0, 0.0], [20.0, -5.0], [22.0, 18.0], [-4.0, 16.0]])
    truth = [hamal.Pose2(-2, -4, 0.3)]
    for i in range(1, poses):
        truth.append(truth[-1].compose(hamal.Pose2(0.5, 0.0, 2 * math.pi / 100)))
    odometry = [truth[i - 1].between(truth[i]).vector() + rng.normal(0, [0.02, 0.02, 0.005])
                for i in range(1, poses)]
    ranges = [[(j, float(np.linalg.norm(beacons[j] - truth[i].translation())) + rng.normal(0, 0.1))
               for j in range(len(beacons))
               if np.linalg.norm(beacons[j] - truth[i].translation()) < 25.0]
              for i in range(poses)]
    surveyed = beacons + rng.normal(0, 2.0, beacons.shape)  # where the map says they are
    return truth, odometry, ranges, beacons, surveyed


def solve(spec="aprilsam", poses=300):
    truth, odometry, ranges, beacons, surveyed = simulate(poses)
    backend = hamal.backend(spec)
    odo_info = np.diag([1 / 0.02**2, 1 / 0.02**2, 1 / 0.005**2])
    dead_reckoning = [truth[0]]
    for i in range(poses):
        new = hamal.Values()
        factors = []
        if i == 0:
            new.insert(x(0), truth[0])
            factors.append(hamal.prior(x(0), truth[0], np.diag([1e4, 1e4, 1e4])))
        else:
            guess = backend.pose(x(i - 1)).compose(hamal.Pose2(odometry[i - 1]))
            new.insert(x(i), guess)
            factors.append(hamal.between(x(i - 1), x(i), odometry[i - 1], odo_info))
            dead_reckoning.append(dead_reckoning[-1].compose(hamal.Pose2(odometry[i - 1])))
        for j, z in ranges[i]:
            if l(j) not in backend and l(j) not in new:
                # The survey is the beacon's guess and a prior of its accuracy
                # (2 m): one range alone does not fix a point.
                new.insert(l(j), surveyed[j])
                factors.append(hamal.landmark_prior(l(j), surveyed[j], np.eye(2) / 2.0**2))
            factors.append(range_only(x(i), l(j), z, 0.1))
        result = backend.update(hamal.Step(i, new, factors))
        if not result.status.ok:
            raise RuntimeError(f"step {i}: {result.status.message}")
    estimate = backend.estimate()
    true_values = hamal.Values.from_numpy(np.array([p.vector() for p in truth]))
    dr_values = hamal.Values.from_numpy(np.array([p.vector() for p in dead_reckoning]))
    return {
        "estimate": estimate,
        "ate": hamal.absolute_trajectory_error(estimate, true_values),
        "ate_dead_reckoning": hamal.absolute_trajectory_error(dr_values, true_values),
        "beacon_error": np.linalg.norm(estimate.landmarks() - beacons, axis=1),
        "surveyed_error": np.linalg.norm(surveyed - beacons, axis=1),
    }


def main():
    check = hamal.check_jacobians(range_only(x(0), l(0), 5.0, 0.1),
                                  accept=lambda v: np.linalg.norm(v.point(l(0)) - v.pose(x(0)).translation()) > 0.1)
    print("Jacobian check:", "ok" if check.ok else "FAILED", f"(max error {check.max_rel_error:.2e})")
    r = solve()
    print(f"trajectory RMSE: {r['ate'].translation_rmse:.3f} m with the beacons, "
          f"{r['ate_dead_reckoning'].translation_rmse:.3f} m from odometry alone")
    print("beacon errors (m):", np.round(r["beacon_error"], 3), "surveyed:", np.round(r["surveyed_error"], 3))


if __name__ == "__main__":
    main()
