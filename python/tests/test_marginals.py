# Marginal covariances from Python (python/README.md, "Marginal covariances"):
# Backend.marginal_covariance and joint_marginal_covariance against the dense
# inverse of H = sum J^T J from Factor.linearize at the estimate, the refusals,
# and calls from several threads at once.
import os
import threading

import numpy as np
import pytest

import hamal
from hamal import x
from conftest import square_world


def dense_covariance(factors, values, keys):
    order = values.keys()
    col = {}
    n = 0
    for k in order:
        col[k] = n
        n += 3
    h = np.zeros((n, n))
    for f in factors:
        _, js = f.linearize(values)
        for a, ka in enumerate(f.keys):
            for b, kb in enumerate(f.keys):
                h[col[ka]:col[ka] + 3, col[kb]:col[kb] + 3] += js[a].T @ js[b]
    inverse = np.linalg.inv(h)
    idx = np.concatenate([np.arange(col[k], col[k] + 3) for k in keys])
    return inverse[np.ix_(idx, idx)]


def solved(spec):
    g, _ = square_world()
    batch = hamal.ThesisProtocol(g).batch()
    b = hamal.backend(spec)
    assert b.update(batch).status.ok
    return b, batch


@pytest.mark.parametrize("spec", ["cholesky", "ceres"])
def test_batch_backends_give_the_dense_inverse_at_the_estimate(spec):
    b, batch = solved(spec)
    keys = [x(11), x(0), x(5)]
    want = dense_covariance(batch.new_factors, b.estimate(), keys)
    joint = b.joint_marginal_covariance(keys)
    assert joint.shape == (9, 9)
    np.testing.assert_allclose(joint, want, rtol=0, atol=1e-9 * np.abs(want).max())
    one = b.marginal_covariance(x(5))
    assert one.shape == (3, 3)
    np.testing.assert_allclose(one, want[6:, 6:], rtol=0, atol=1e-9 * np.abs(want).max())


@pytest.mark.parametrize("spec", ["aprilsam", "aprilsam-top"])
def test_aprilsam_gives_the_dense_inverse_at_its_linearisation_points(spec):
    # AprilSAM's R is at its linearisation points, which lag the estimate:
    # started at the optimum, its batch linearises there.
    optimum, batch = solved("cholesky")
    b = hamal.backend(spec)
    assert b.update(hamal.Step(0, optimum.estimate(), list(batch.new_factors))).status.ok
    keys = [x(11), x(3)]
    want = dense_covariance(batch.new_factors, optimum.estimate(), keys)
    np.testing.assert_allclose(b.joint_marginal_covariance(keys), want, rtol=0,
                               atol=1e-9 * np.abs(want).max())


def test_a_fixed_pose_has_zero_covariance():
    g, _ = square_world()
    b = hamal.backend("cholesky")
    values = hamal.ThesisProtocol(g).initial_values()
    assert b.update(hamal.Step(0, values, list(g.factors), [x(0)])).status.ok
    assert not b.marginal_covariance(x(0)).any()
    assert np.all(np.linalg.eigvalsh(b.marginal_covariance(x(6))) > 0)


def test_refusals():
    b, _ = solved("cholesky")
    with pytest.raises(hamal.Error, match="does not hold"):
        b.marginal_covariance(x(99))
    with pytest.raises(hamal.Error, match="asked twice"):
        b.joint_marginal_covariance([x(1), x(1)])
    # Nothing anchors a lone odometry pair: the update fails, and so does
    # the covariance, with the update's reason.
    g, _ = square_world()
    failed = hamal.backend("cholesky")
    values = hamal.ThesisProtocol(g).initial_values()
    assert not failed.update(hamal.Step(0, values, list(g.factors))).status.ok
    with pytest.raises(RuntimeError, match="last update did not end ok"):
        failed.marginal_covariance(x(1))


def test_threads_share_a_backend():
    b, _ = solved("ceres")
    want = b.joint_marginal_covariance([x(11), x(4)])
    got = []

    def ask():
        for _ in range(5):
            got.append(b.joint_marginal_covariance([x(11), x(4)]))

    threads = [threading.Thread(target=ask) for _ in range(4)]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    assert len(got) == 20
    for m in got:
        np.testing.assert_array_equal(m, want)


def test_a_backend_without_them_is_a_type_error():
    path = os.environ.get("HAMAL_EXAMPLE_PLUGIN")
    if not path or not os.path.isfile(path):
        pytest.skip("HAMAL_EXAMPLE_PLUGIN (build/plugins/libhamal_example_plugin.so) not given")
    if not any(b["name"] == "dense-gauss-newton" for b in hamal.list_backends()):
        hamal.load_plugin(path)
    g, _ = square_world()
    b = hamal.backend("dense-gauss-newton")
    b.update(hamal.ThesisProtocol(g).batch())
    with pytest.raises(TypeError, match="does not offer marginal covariances"):
        b.marginal_covariance(x(1))
