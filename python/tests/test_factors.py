# Factor kinds by name through the registry, numpy argument checks, and a
# plugin's kind.
import os

import numpy as np
import pytest

import hamal
from hamal import l, x

I3 = np.diag([100.0, 50.0, 400.0])
I2 = np.array([[10.0, 1.0], [1.0, 20.0]])


def test_every_builtin_kind_by_name_is_the_readers_factor():
    b = hamal.between(x(0), x(1), hamal.Pose2(1, 0.1, 0.2), I3)
    cases = {
        "EDGE_SE2": b,
        "EDGE_SE2_PRIOR": hamal.prior(x(0), [0.1, 0.2, 0.3], I3),
        "EDGE_SE2_POSITION": hamal.position(x(2), [3, 4], I2),
        "EDGE_SE2_XY": hamal.pose_point(x(1), l(2), [0.5, 0.25], I2),
        "EDGE_SE2_RANGE_BEARING": hamal.range_bearing(x(1), l(2), 2.0, 0.3, I2),
        "EDGE_XY_PRIOR": hamal.landmark_prior(l(2), [1, 2], I2),
        "EDGE_SE2_L2G": hamal.l2g(x(3), 7, hamal.Pose2(5, 5, 1), [1, 0, 0.1], I3),
        "EDGE_MAXMIX": hamal.max_mixture(b, 0.01, 1e-6),
    }
    for tag, f in cases.items():
        assert f.tag == tag
        again = hamal.parse_factor(f.line())  # the g2o reader's factor for the same line
        assert again.line() == f.line()
    assert hamal.factor("between", x(0), x(1), [1, 0.1, 0.2], I3).line() == b.line()
    assert hamal.factor("EDGE_SE2", x(0), x(1), hamal.Pose2(1, 0.1, 0.2), I3).line() == b.line()
    assert b.keys == [x(0), x(1)] and b.dims == [3, 3] and b.residual_dim == 3
    # Full precision: the numbers read back bit for bit.
    f = hamal.between(x(0), x(1), [0.1, 1 / 3, np.pi], I3 / 3)
    assert f.line() == hamal.parse_factor(f.line()).line()


def test_residual_jacobians_and_chi2_of_a_factor():
    f = hamal.between(x(0), x(1), [1, 0, 0], np.diag([4.0, 4.0, 9.0]))
    v = hamal.Values()
    v.insert(x(0), hamal.Pose2())
    v.insert(x(1), hamal.Pose2(1.5, 0, 0.1))
    r = f.residual(v)
    assert np.allclose(r, [2 * 0.5, 0, 3 * 0.1])
    assert f.chi2(v) == pytest.approx(1 + 0.09)
    res, js = f.linearize(v)
    assert np.allclose(res, r) and len(js) == 2 and js[0].shape == (3, 3)
    assert hamal.chi2([f, f], v) == pytest.approx(2 * f.chi2(v))
    frm, to, z, info = f.relative_pose()
    assert (frm, to) == (x(0), x(1)) and np.allclose(info, np.diag([4, 4, 9]))
    with pytest.raises(hamal.Error, match="x0 does not exist"):
        f.residual(hamal.Values())


@pytest.mark.parametrize("args, message", [
    ((x(0), x(1), [1, 0], I3), r"measurement: expected shape \(3,\), got \(2,\)"),
    ((x(0), x(1), [1, 0, 0], np.eye(2)), r"information: expected shape \(3, 3\), got \(2, 2\)"),
    ((x(0), x(1), [1, 0, np.nan], I3), "measurement: has non-finite entries"),
    ((x(0), x(1), [1, 0, 0], np.array([[1, 2, 0], [0, 1, 0], [0, 0, 1.0]])), "information: .*not symmetric"),
    ((x(0), x(1), [1, 0, 0], -np.eye(3)), "information: .*not positive definite"),
    ((x(0), x(1), ["a", "b", "c"], I3), "measurement: expected real numbers"),
    ((l(0), x(1), [1, 0, 0], I3), "a: expected a key of kind 'x'"),
    ((x(0), -1, [1, 0, 0], I3), "b: expected hamal.x"),
])
def test_bad_arguments_name_the_argument(args, message):
    with pytest.raises(hamal.Error, match=message):
        hamal.between(*args)


def test_other_kinds_check_their_arguments():
    with pytest.raises(hamal.Error, match="range: expected shape"):
        hamal.range_bearing(x(0), l(1), [1, 2], 0.1, I2)
    with pytest.raises(hamal.Error, match="null_weight: has non-finite"):
        hamal.max_mixture(hamal.prior(x(0), [0, 0, 0], I3), float("inf"), 1e-6)
    with pytest.raises(hamal.Error, match="nominal: expected a hamal.Factor"):
        hamal.max_mixture("EDGE_SE2", 0.1, 1e-6)
    with pytest.raises(hamal.Error, match="landmark: expected a key of kind 'l'"):
        hamal.pose_point(x(0), x(1), [1, 2], I2)
    # The registry's own checks stay: a weight outside (0, 1).
    with pytest.raises(hamal.Error):
        hamal.max_mixture(hamal.prior(x(0), [0, 0, 0], I3), 2.0, 1e-6)
    with pytest.raises(hamal.Error, match="EDGE_NOPE"):
        hamal.factor("EDGE_NOPE", x(0))


def test_a_plugins_kind_by_its_tag():
    path = os.environ.get("HAMAL_EXAMPLE_PLUGIN")
    if not path or not os.path.isfile(path):
        pytest.skip("HAMAL_EXAMPLE_PLUGIN (build/plugins/libhamal_example_plugin.so) not given")
    if not any(f["tag"] == "EDGE_SE2_CAUCHY" for f in hamal.list_factors()):
        hamal.load_plugin(path)
    assert any(b["name"] == "dense-gauss-newton" for b in hamal.list_backends())
    f = hamal.factor("EDGE_SE2_CAUCHY", x(0), x(1), hamal.Pose2(1, 0, 0), np.eye(3), 0.5)
    assert f.tag == "EDGE_SE2_CAUCHY" and f.has_loss
    with pytest.raises(hamal.Error, match="libnothing"):
        hamal.load_plugin("/nonexistent/libnothing.so")


def test_a_robust_loss_changes_the_linearisation_not_chi2():
    v = hamal.Values()
    v.insert(x(0), hamal.Pose2())
    v.insert(x(1), hamal.Pose2(4, 0, 0))
    f = hamal.between(x(0), x(1), [1, 0, 0], np.eye(3))
    plain, _ = f.linearize(v)
    f.set_loss("huber", 1.0)
    assert f.has_loss and f.chi2(v) == pytest.approx(9.0)
    robust, _ = f.linearize(v)
    assert np.linalg.norm(robust) < np.linalg.norm(plain)  # the Triggs correction shrinks it
    f.set_loss(None)
    assert not f.has_loss
    with pytest.raises(hamal.Error, match="kind: unknown loss 'l1'"):
        f.set_loss("l1")
    with pytest.raises(hamal.Error, match="scale: must be positive"):
        f.set_loss("cauchy", -1)
