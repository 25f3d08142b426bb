# Keys, Pose2, Point2 and Values, and their numpy conversions.
import math
import pickle

import numpy as np
import pytest

import hamal


def test_keys_name_poses_and_landmarks_apart():
    assert hamal.x(3) == hamal.Key("x", 3)
    assert hamal.x(3) != hamal.l(3)
    assert str(hamal.x(3)) == "x3" and repr(hamal.l(7)) == "l(7)"
    assert hamal.x(3).kind == "x" and hamal.l(7).index == 7
    assert len({hamal.x(1), hamal.x(1), hamal.l(1)}) == 2
    assert sorted([hamal.x(2), hamal.l(5), hamal.x(1)]) == [hamal.l(5), hamal.x(1), hamal.x(2)]
    assert pickle.loads(pickle.dumps(hamal.l(9))) == hamal.l(9)
    with pytest.raises(hamal.Error, match="one letter"):
        hamal.Key("xy", 1)


def test_pose2_composes_as_the_cpp_pose():
    a, b = hamal.Pose2(1, 2, 0.5), hamal.Pose2(-0.3, 0.7, 2.9)
    ab = a.compose(b)
    m = a.matrix() @ b.matrix()
    assert np.allclose([ab.x, ab.y], m[:2, 2]) and math.isclose(ab.theta, hamal.wrap_angle(3.4))
    assert (a * b) == ab
    assert np.allclose(a.between(ab).vector(), b.vector())
    assert np.allclose(a.compose(a.inverse()).vector(), 0)
    p = np.array([0.3, -1.0])
    assert np.allclose(a.transform_to(a.transform_from(p)), p)
    assert hamal.Pose2(np.array([1, 2, 3])) == hamal.Pose2(1, 2, 3)
    with pytest.raises(hamal.Error, match="not finite"):
        hamal.Pose2(0, float("nan"), 0)
    with pytest.raises(hamal.Error, match=r"Pose2: expected shape \(3,\), got \(2,\)"):
        hamal.Pose2(np.zeros(2))


def test_point2_is_a_numpy_array():
    p = hamal.Point2(1.5, -2)
    assert isinstance(p, np.ndarray) and p.shape == (2,) and p.dtype == np.float64


def test_values_hold_poses_and_points():
    v = hamal.Values()
    v.insert(hamal.x(0), hamal.Pose2(1, 2, 3))
    v.insert(hamal.l(4), [5, 6])
    assert len(v) == 2 and hamal.x(0) in v and hamal.x(1) not in v
    assert v.pose(hamal.x(0)) == hamal.Pose2(1, 2, 3)
    assert np.array_equal(v.point(hamal.l(4)), [5, 6])
    assert v.type(hamal.l(4)) == "Point2" and v.dim(hamal.x(0)) == 3
    assert v.keys() == [hamal.l(4), hamal.x(0)]
    with pytest.raises(hamal.Error):
        v.insert(hamal.x(0), hamal.Pose2())
    with pytest.raises(hamal.Error):
        v.point(hamal.x(0))  # a pose, not a point
    with pytest.raises(hamal.Error, match=r"value of l5: expected shape \(2,\), got \(3,\)"):
        v.insert(hamal.l(5), [1, 2, 3])
    with pytest.raises(hamal.Error, match="value of l5: entry 1 is inf"):
        v.insert(hamal.l(5), [1, float("inf")])
    with pytest.raises(hamal.Error, match="value of l5: expected real numbers.*dtype <U1"):
        v.insert(hamal.l(5), ["a", "b"])
    w = v.copy()
    w.set(hamal.x(0), hamal.Pose2())
    assert v.pose(hamal.x(0)) == hamal.Pose2(1, 2, 3)


def test_numpy_round_trip_of_poses_and_landmarks():
    rng = np.random.default_rng(1)
    poses = rng.uniform(-10, 10, (50, 3))
    poses[:, 2] = rng.uniform(-3, 3, 50)
    landmarks = rng.uniform(-10, 10, (7, 2))
    v = hamal.Values.from_numpy(poses, landmarks, pose_ids=np.arange(100, 150), landmark_ids=[3, 1, 4, 15, 9, 2, 6])
    assert np.array_equal(v.poses(), poses)  # bit for bit, ids sorted
    assert np.array_equal(v.pose_ids(), np.arange(100, 150))
    order = np.argsort([3, 1, 4, 15, 9, 2, 6])
    assert np.array_equal(v.landmarks(), landmarks[order])
    assert np.array_equal(v.landmark_ids(), np.sort([3, 1, 4, 15, 9, 2, 6]))
    assert v.pose(hamal.x(100)) == hamal.Pose2(*poses[0])


def test_numpy_arguments_are_checked_before_anything_is_inserted():
    v = hamal.Values()
    with pytest.raises(hamal.Error, match=r"poses: expected shape \(N, 3\), got \(4, 2\)"):
        v.insert_poses(np.arange(4), np.zeros((4, 2)))
    with pytest.raises(hamal.Error, match=r"ids: expected shape \(4,\), got \(3,\)"):
        v.insert_poses(np.arange(3), np.zeros((4, 3)))
    bad = np.zeros((4, 3))
    bad[2, 1] = np.nan
    with pytest.raises(hamal.Error, match="poses: entry 7 is nan"):
        v.insert_poses(np.arange(4), bad)
    with pytest.raises(hamal.Error, match="ids: x1 appears twice"):
        v.insert_poses([0, 1, 1, 2], np.zeros((4, 3)))
    with pytest.raises(hamal.Error, match="ids: entry 0 is not a non-negative integer id"):
        v.insert_poses([-1, 1, 2, 3], np.zeros((4, 3)))
    with pytest.raises(hamal.Error, match="complex"):
        v.insert_landmarks([0], np.zeros((1, 2), dtype=complex))
    assert len(v) == 0


def test_hundred_thousand_poses_to_numpy_without_a_python_loop():
    n = 100_000
    poses = np.column_stack([np.arange(n, dtype=float), np.zeros(n), np.full(n, 0.25)])
    v = hamal.Values.from_numpy(poses)
    assert len(v) == n
    out = v.poses()
    assert out.shape == (n, 3) and np.array_equal(out, poses)
