# Back-ends by spec, UpdateResult, the listings, step sources, metrics, LAGO.
import numpy as np
import pytest

import hamal
from hamal import x
from conftest import square_world

BACKENDS = ["aprilsam", "aprilsam-top", "cholesky", "ceres"]


def test_listings_give_each_option_with_meaning_and_default():
    backends = {b["name"]: b for b in hamal.list_backends()}
    assert {"aprilsam", "cholesky", "ceres"} <= set(backends)
    delta = {o["name"]: o for o in backends["aprilsam"]["options"]}["delta_t"]
    assert delta["default"] and delta["help"]
    factors = {(f["format"], f["tag"]) for f in hamal.list_factors()}
    assert ("g2o", "EDGE_SE2") in factors and ("toro", "EDGE2") in factors
    assert "aprilsam" in hamal.describe_backends() and "EDGE_SE2" in hamal.describe_factors()


def test_backend_by_spec_and_its_errors():
    b = hamal.backend("aprilsam:delta_t=0.1")
    assert b.spec == "aprilsam:delta_t=0.1" and b.options["delta_t"] == "0.1"
    with pytest.raises(hamal.Error, match="unknown back-end 'nope'; registered: .*aprilsam"):
        hamal.backend("nope")
    with pytest.raises(hamal.Error, match="delta_tt"):
        hamal.backend("aprilsam:delta_tt=0.1")
    with pytest.raises(hamal.Error):
        hamal.backend("aprilsam:delta_t")


@pytest.mark.parametrize("spec", BACKENDS)
def test_protocol_steps_every_backend_to_the_optimum(spec):
    g, truth = square_world()
    protocol = hamal.ThesisProtocol(g)
    b = hamal.backend(spec)
    results = [b.update(step) for step in protocol.steps(b)]
    assert len(results) == len(protocol) == 12
    assert all(r.status.ok for r in results)
    assert {r.kind for r in results} <= {"batch", "incremental", "none"}
    r = results[-1]
    assert isinstance(r.reason, str) and r.time.total() >= 0 and r.seconds > 0
    assert r.variables == 12 and r.status.code == "ok" and r.status.keys == []
    batch = hamal.backend("cholesky")
    batch.update(protocol.batch())
    optimum = hamal.chi2(g.factors, batch.estimate())
    # aprilsam relinearises only what moved enough: near the optimum, not at it.
    assert hamal.chi2(g.factors, b.estimate()) == pytest.approx(optimum, rel=1e-3)
    assert hamal.chi2(g.factors, protocol.initial_values()) > 10 * optimum


def test_run_loop_gives_times_chi2_and_estimate():
    g, _ = square_world()
    run = hamal.run(g, "aprilsam")
    assert len(run.results) == 12 and run.seconds.shape == (12,)
    assert len(run.factors) == len(g)  # the prior is not a dataset factor
    assert run.chi2 == pytest.approx(hamal.chi2(g.factors, run.estimate))
    assert run.not_ok == 0 and run.batches >= 1
    assert len(hamal.run(g, hamal.backend("cholesky"), max_steps=5).results) == 5


def test_a_bad_step_raises_and_leaves_the_backend_unchanged():
    g, _ = square_world()
    protocol = hamal.ThesisProtocol(g)
    b = hamal.backend("aprilsam")
    it = protocol.steps(b)
    b.update(next(it))
    before = b.estimate().poses()
    bad = hamal.Step(1, hamal.Values(), [hamal.between(x(0), x(40), [1, 0, 0], np.eye(3))])
    with pytest.raises(hamal.Error, match="x40"):
        b.update(bad)
    assert np.array_equal(b.estimate().poses(), before)
    b.update(next(it))  # and it goes on
    assert len(b.estimate()) == 2


def test_steps_built_by_hand():
    b = hamal.backend("cholesky")
    v = hamal.Values()
    v.insert(x(0), hamal.Pose2(0.1, 0, 0))
    v.insert(x(1), hamal.Pose2(1.2, 0.1, 0))
    b.update(hamal.Step(0, v, [hamal.between(x(0), x(1), [1, 0, 0], np.eye(3))], fixed=[x(0)]))
    e = b.estimate()
    assert e.pose(x(0)) == hamal.Pose2(0.1, 0, 0)  # fixed
    assert np.allclose(e.pose(x(1)).vector(), [1.1, 0, 0])
    assert b.pose(x(1)) == e.pose(x(1)) and x(1) in b and hamal.l(0) not in b and len(b) == 2
    with pytest.raises(hamal.Error):
        b.point(x(1))


def test_step_by_index_from_an_estimate():
    g, _ = square_world()
    p = hamal.ThesisProtocol(g, add_prior=False)
    assert p.prior is None and p.pose(3) == x(3)
    s0 = p.step(0, hamal.Values())
    assert len(s0.new_values) == 1 and s0.new_factors == []
    with pytest.raises(hamal.Error, match="index 99"):
        p.step(99, hamal.Values())
    with pytest.raises(hamal.Error, match="prior_information: entry"):
        hamal.ThesisProtocol(g, prior_information=[1, np.nan, 1])


def test_trajectory_error_after_alignment():
    _, truth = square_world()
    t = hamal.Values.from_numpy(np.array([p.vector() for p in truth]))
    moved = hamal.Values.from_numpy(np.array([hamal.Pose2(3, -2, 0.7).compose(p).vector() for p in truth]))
    aligned = hamal.absolute_trajectory_error(moved, t)
    assert aligned.poses == 12 and aligned.translation_rmse < 1e-9 and aligned.rotation_rmse < 1e-9
    assert hamal.absolute_trajectory_error(moved, t, align=False).translation_rmse > 1


def test_lago_starts_next_to_the_optimum():
    g, truth = square_world()
    initial = hamal.ThesisProtocol(g).initial_values()
    result = hamal.lago(g, initial)
    assert result.poses == 12 and result.edges == 12 and result.unused == []
    assert "LAGO" in result.describe()
    assert hamal.chi2(g.factors, result.values) < hamal.chi2(g.factors, initial)


def test_status_codes_name_every_outcome():
    assert hamal.STATUS_CODES == ("ok", "numerical_failure", "not_converged", "uncertain")


def test_a_backend_that_spends_its_iterations_is_not_converged():
    g, _ = square_world()
    b = hamal.backend("cholesky:max_iterations=1")
    r = b.update(hamal.ThesisProtocol(g).batch())
    assert r.status.code == "not_converged" and not r.status and "1 iterations" in r.status.message
