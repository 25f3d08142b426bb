# Factors written in Python: against their C++ twin, in every back-end,
# through the Jacobian checker, and when the callable misbehaves.
import os
import sys

import numpy as np
import pytest

import hamal
from hamal import x
from conftest import square_world

sys.path.insert(0, os.path.join(os.path.dirname(__file__), "..", "examples"))
from python_between import between as python_between, between_function  # noqa: E402


def twin_graphs():
    g, _ = square_world()
    twin = hamal.Graph()
    for f in g.factors:
        a, b, z, info = f.relative_pose()
        twin.add(python_between(a, b, z.vector(), info))
    return g, twin


def test_python_factor_matches_its_cpp_twin_to_1e9():
    rng = np.random.default_rng(3)
    info = np.array([[50.0, 3, 1], [3, 80, -2], [1, -2, 300]])
    z = [0.7, -0.2, 0.4]
    cpp = hamal.between(x(0), x(1), z, info)
    py = python_between(x(0), x(1), z, info)
    for _ in range(50):
        v = hamal.Values.from_numpy(rng.uniform(-3, 3, (2, 3)))
        r1, j1 = cpp.linearize(v)
        r2, j2 = py.linearize(v)
        assert np.max(np.abs(r1 - r2)) < 1e-9
        assert all(np.max(np.abs(a - b)) < 1e-9 for a, b in zip(j1, j2))
        assert abs(cpp.chi2(v) - py.chi2(v)) < 1e-9


# ceres:threads=2 evaluates from Ceres' worker threads, each taking the GIL
# that update() released.
@pytest.mark.parametrize("spec", ["ceres", "ceres:threads=2", "cholesky", "aprilsam"])
def test_python_factors_solve_as_their_twins_in_every_backend(spec):
    g, twin = twin_graphs()
    cpp = hamal.run(g, spec)
    py = hamal.run(twin, spec)
    assert py.not_ok == 0
    assert np.max(np.abs(cpp.estimate.poses() - py.estimate.poses())) < 1e-9
    assert abs(cpp.chi2 - py.chi2) < 1e-9


def test_python_and_cpp_factors_in_one_run():
    g, twin = twin_graphs()
    mixed = hamal.Graph()
    for i, (a, b) in enumerate(zip(g.factors, twin.factors)):
        mixed.add(a if i % 2 else b)
    run = hamal.run(mixed, "aprilsam")
    assert abs(run.chi2 - hamal.run(g, "aprilsam").chi2) < 1e-9


def test_check_jacobians_on_a_python_factor():
    z, info = [1, 0, 0.1], np.diag([10.0, 10, 40])
    r = hamal.check_jacobians(python_between(x(0), x(1), z, info), trials=50)
    assert r.ok and r.trials == 50, r.report
    good = between_function(z, info)

    def broken(params):
        res, (ja, jb) = good(params)
        jb = jb.copy()
        jb[0, 2] += 1.0  # a wrong entry
        return res, [ja, jb]

    r = hamal.check_jacobians(hamal.PythonFactor([x(0), x(1)], 3, broken), trials=20)
    assert not r.ok and r.worst_block == 1 and r.worst_col == 2, r.report


def one_pose_backend(spec="aprilsam"):
    b = hamal.backend(spec)
    v = hamal.Values()
    v.insert(x(0), hamal.Pose2())
    b.update(hamal.Step(0, v, [hamal.prior(x(0), [0, 0, 0], np.eye(3))]))
    return b


@pytest.mark.parametrize("callable_, message", [
    (lambda p: 1 / 0, "python_factor: the callable raised ZeroDivisionError"),
    (lambda p: (np.zeros(2), [np.zeros((1, 3))]), r"the residual: expected shape \(1,\), got \(2,\)"),
    (lambda p: (np.zeros(1), [np.zeros((1, 2))]), r"Jacobian 0: expected shape \(1, 3\), got \(1, 2\)"),
    (lambda p: (np.zeros(1), []), "returned 0 Jacobians, expected 1"),
    (lambda p: np.zeros(1), "expected a tuple"),
    (lambda p: (np.array(["a"]), [np.zeros((1, 3))]), "the residual: expected real numbers.*dtype <U1"),
    (lambda p: (np.array([np.nan]), [np.zeros((1, 3))]), "the residual: entry 0 is nan"),
    (lambda p: (np.zeros(1), [np.full((1, 3), np.inf)]), "Jacobian 0: entry 0 is inf"),
])
@pytest.mark.parametrize("spec", ["aprilsam", "ceres", "cholesky"])
def test_a_broken_callable_raises_and_leaves_the_backend_unchanged(spec, callable_, message):
    b = one_pose_backend(spec)
    before = b.estimate().poses()
    v = hamal.Values()
    v.insert(x(1), hamal.Pose2(1, 0, 0))
    f = hamal.PythonFactor([x(1)], 1, callable_, name="python_factor")
    step = hamal.Step(1, v, [hamal.between(x(0), x(1), [1, 0, 0], np.eye(3)), f])
    with pytest.raises(hamal.Error, match=message):
        b.update(step)
    assert len(b.estimate()) == 1 and np.array_equal(b.estimate().poses(), before)


def test_python_factor_arguments_are_checked():
    with pytest.raises(hamal.Error, match="keys: expected hamal.Key entries"):
        hamal.PythonFactor([0, 1], 3, lambda p: None)
    with pytest.raises(hamal.Error, match="residual_dim: must be >= 1"):
        hamal.PythonFactor([x(0)], 0, lambda p: None)
    with pytest.raises(hamal.Error, match="function: is not callable"):
        hamal.PythonFactor([x(0)], 1, 42)
    with pytest.raises(hamal.Error, match="dims: 1 entries for 2 keys"):
        hamal.PythonFactor([x(0), x(1)], 1, lambda p: None, dims=[3])
    with pytest.raises(hamal.Error, match="neither a pose nor a landmark"):
        hamal.PythonFactor([hamal.Key("q", 0)], 1, lambda p: None)


def test_a_later_failure_is_a_status_that_names_the_python_error():
    calls = {"n": 0}

    def flaky(params):
        calls["n"] += 1
        if calls["n"] > 1:
            raise RuntimeError("sensor model undefined here")
        return np.array([params[0][0] - 1.0]), [np.array([[1.0, 0, 0]])]

    b = one_pose_backend("cholesky")
    v = hamal.Values()
    v.insert(x(1), hamal.Pose2(1, 0, 0))
    f = hamal.PythonFactor([x(1)], 1, flaky, name="flaky")
    r = b.update(hamal.Step(1, v, [hamal.between(x(0), x(1), [1, 0, 0], np.eye(3)), f]))
    assert not r.status.ok
    assert "flaky: the callable raised RuntimeError: sensor model undefined here" in r.status.message
    assert f.failures >= 1 and "sensor model" in f.last_error


class Prior1D(hamal.PythonFactor):
    """A subclass, as GTSAM users write CustomFactor subclasses."""

    def __init__(self, key, target):
        self.target = target
        super().__init__([key], 1, self.evaluate, name="prior1d")

    def evaluate(self, params):
        return np.array([params[0][0] - self.target]), [np.array([[1.0, 0, 0]])]


def test_a_subclass_of_python_factor_is_solved_and_stays_itself():
    f = Prior1D(x(0), 2.0)
    v = hamal.Values()
    v.insert(x(0), hamal.Pose2(5, 0, 0))
    b = hamal.backend("cholesky")
    b.update(hamal.Step(0, v, [f, hamal.prior(x(0), [0, 0, 0], np.eye(3))]))
    assert np.allclose(b.pose(x(0)).vector(), [1, 0, 0])  # halfway between the two priors
    g = hamal.Graph()
    g.add(f)
    assert type(g.factors[0]) is Prior1D and g.factors[0].target == 2.0


def test_check_jacobians_shows_the_exception_of_a_factor_that_raises():
    def residual(params):
        raise KeyError("no such beacon")

    r = hamal.check_jacobians(hamal.PythonFactor([x(0)], 1, residual), trials=5)
    assert not r.ok
    assert r.python_error == "KeyError: 'no such beacon'"
    assert "KeyError: 'no such beacon'" in r.report and "At:" not in r.report

    calls = []

    def sometimes(params):  # fails on the first evaluation only: the check goes on
        calls.append(1)
        if len(calls) == 1:
            raise ZeroDivisionError("first call")
        return np.array([params[0][0]]), [np.array([[1.0, 0.0, 0.0]])]

    r = hamal.check_jacobians(hamal.PythonFactor([x(0)], 1, sometimes), trials=5)
    assert r.ok and r.python_error == "ZeroDivisionError: first call" and "first call" in r.report


def test_check_jacobians_of_a_good_factor_has_no_python_error():
    f = hamal.PythonFactor([x(0)], 1, lambda p: (np.array([p[0][1]]), [np.array([[0.0, 1.0, 0.0]])]))
    r = hamal.check_jacobians(f, trials=5)
    assert r.ok and r.python_error == "" and "Python" not in r.report
