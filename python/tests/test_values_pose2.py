# Values as a Python mapping (iteration, items, len, pickle, multiprocessing)
# and numpy in both directions; Pose2 as an element of SE(2): identity,
# compose, inverse, between, exp/log and vectorised point transforms
# (python/README.md, "numpy, pickle, SE(2)").
import math
import multiprocessing
import pickle

import numpy as np
import pytest

import hamal
from hamal import Pose2, l, x


def small_values():
    v = hamal.Values()
    v.insert(x(2), Pose2(1.0, -2.0, 0.3))
    v.insert(x(0), Pose2(0.5, 0.25, -3.0))
    v.insert(l(7), [4.0, 5.5])
    return v


def test_values_iterate_over_sorted_keys_and_items():
    v = small_values()
    assert len(v) == 3
    assert list(v) == [l(7), x(0), x(2)] == v.keys()
    items = v.items()
    assert [k for k, _ in items] == list(v)
    assert items[1][1] == Pose2(0.5, 0.25, -3.0) and isinstance(items[2][1], Pose2)
    assert np.array_equal(items[0][1], [4.0, 5.5])
    assert dict(items)[x(2)] == v[x(2)]
    for k in v:  # iterating a snapshot: changing the Values meanwhile is safe
        v.erase(k)
    assert len(v) == 0


def test_values_pickle_round_trip_is_exact():
    v = small_values()
    v.insert(hamal.Key("m", 3), Pose2(1e-300, math.pi, 1.0))
    w = pickle.loads(pickle.dumps(v))
    assert w.keys() == v.keys()
    for k in v:
        assert np.array_equal(np.asarray(w[k]), np.asarray(v[k])) and w.type(k) == v.type(k)
    assert len(pickle.loads(pickle.dumps(hamal.Values()))) == 0


@pytest.mark.parametrize("state", [
    (b"x", np.array([1], np.uint64), np.array([0], np.uint8), np.array([[0.0, 0.0]])),  # shape
    (b"x", np.array([2**60], np.uint64), np.array([0], np.uint8), np.zeros((1, 3))),    # index
    (b"x", np.array([1], np.uint64), np.array([5], np.uint8), np.zeros((1, 3))),        # type
    (b"xx", np.array([1, 1], np.uint64), np.array([0, 0], np.uint8), np.zeros((2, 3))),  # twice
    (b"x", np.array([1], np.uint64), np.array([0], np.uint8), np.array([[np.nan, 0, 0]])),
])
def test_a_bad_pickled_state_is_refused(state):
    v = hamal.Values.__new__(hamal.Values)
    with pytest.raises(hamal.Error):
        v.__setstate__(state)


def solve_square(poses):
    """A process' work: a small graph solved, its estimate returned (pickled)."""
    from conftest import square_world
    g, _ = square_world(poses)
    return hamal.run(g, "cholesky").estimate


def test_multiprocessing_returns_an_estimate():
    with multiprocessing.get_context("fork").Pool(2) as pool:
        estimates = pool.map(solve_square, [6, 9])
    assert [len(e) for e in estimates] == [6, 9]
    assert np.allclose(estimates[0].poses(), solve_square(6).poses(), atol=1e-12)


def test_values_to_numpy_and_back():
    v = small_values()
    poses, landmarks, pose_ids, landmark_ids = v.to_numpy()
    assert poses.shape == (2, 3) and landmarks.shape == (1, 2)
    assert pose_ids.tolist() == [0, 2] and landmark_ids.tolist() == [7]
    assert np.array_equal(poses[1], np.asarray(v[x(2)]))
    w = hamal.Values.from_numpy(*v.to_numpy())
    assert w.keys() == v.keys() and all(np.array_equal(np.asarray(w[k]), np.asarray(v[k])) for k in v)
    only_poses = hamal.Values.from_numpy(*hamal.Values.from_numpy(np.ones((4, 3))).to_numpy())
    assert len(only_poses) == 4 and only_poses.pose_ids().tolist() == [0, 1, 2, 3]
    v.insert(hamal.Key("m", 1), Pose2())
    with pytest.raises(hamal.Error, match="m1"):
        v.to_numpy()


def test_np_asarray_of_a_pose_is_a_float_array():
    a = np.asarray(Pose2(1.5, -2.0, 0.25))
    assert a.dtype == np.float64 and a.shape == (3,) and a.tolist() == [1.5, -2.0, 0.25]
    assert np.asarray(Pose2(1, 2, 3), dtype=np.float32).dtype == np.float32
    stacked = np.array([Pose2(1, 0, 0), Pose2(0, 1, 0.5)])
    assert stacked.dtype == np.float64 and stacked.shape == (2, 3)
    assert Pose2(np.asarray(Pose2(1, 2, 0.5))) == Pose2(1, 2, 0.5)


def random_poses(n, seed=3):
    rng = np.random.default_rng(seed)
    return [Pose2(*rng.uniform(-5, 5, 2), rng.uniform(-math.pi, math.pi)) for _ in range(n)]


def assert_pose_close(a, b, tol=1e-9):
    assert abs(a.x - b.x) < tol and abs(a.y - b.y) < tol
    assert abs(hamal.wrap_angle(a.theta - b.theta)) < tol, (a, b)


def test_group_operations():
    e = Pose2.identity()
    assert e == Pose2(0, 0, 0)
    for p, q in zip(random_poses(20), random_poses(20, seed=4)):
        assert_pose_close(p * e, p)
        assert_pose_close(p * p.inverse(), e)
        assert_pose_close(p.between(q), p.inverse() * q)
        assert_pose_close(p * p.between(q), q)
        assert np.allclose((p * q).matrix(), p.matrix() @ q.matrix())


def se2_hat_exp(xi, terms=40):
    """exp of the 3 x 3 se(2) matrix [[0, -w, vx], [w, 0, vy], [0, 0, 0]] by its series."""
    a = np.array([[0, -xi[2], xi[0]], [xi[2], 0, xi[1]], [0, 0, 0]], dtype=float)
    out, term = np.eye(3), np.eye(3)
    for k in range(1, terms):
        term = term @ a / k
        out = out + term
    return out


@pytest.mark.parametrize("xi", [[1.0, 2.0, 0.5], [-0.3, 0.7, 3.0], [2.0, -1.0, -2.9], [1.0, 0.5, 1e-9],
                                [0.0, 0.0, 0.0], [1.0, -2.0, 1e-4]])
def test_exp_matches_the_matrix_exponential_and_small_steps(xi):
    p = Pose2.exp(xi)
    assert np.allclose(p.matrix(), se2_hat_exp(xi), atol=1e-12)
    # the same motion integrated as 10^4 small body-frame steps
    n = 10000
    q = Pose2.identity()
    step = Pose2(xi[0] / n, xi[1] / n, xi[2] / n)
    for _ in range(n):
        q = q * step
    assert_pose_close(p, q, tol=1e-3)
    assert np.allclose(p.log(), xi, atol=1e-9)


def test_exp_of_log_is_the_pose():
    for p in random_poses(200) + [Pose2(1, 2, math.pi), Pose2(1, 2, 1e-12), Pose2(-3, 0.5, -math.pi + 1e-9)]:
        assert_pose_close(Pose2.exp(p.log()), p, tol=1e-9)
        assert -math.pi < p.log()[2] <= math.pi


def test_transform_points_vectorised():
    p = Pose2(1.0, -2.0, 0.7)
    pts = np.random.default_rng(5).uniform(-10, 10, (100, 2))
    out = p.transform_from(pts)
    assert out.shape == (100, 2)
    assert np.allclose(out, [p.transform_from(q) for q in pts])
    assert np.allclose(out, (p.matrix() @ np.c_[pts, np.ones(100)].T).T[:, :2])
    assert np.allclose(p.transform_to(out), pts)
    assert p.transform_from(np.zeros((0, 2))).shape == (0, 2)
    with pytest.raises(hamal.Error, match="point"):
        p.transform_from(np.zeros((3, 3)))
    with pytest.raises(hamal.Error, match="point"):
        p.transform_from([[np.nan, 0.0]])
