# hamal.plot (python/hamal/plot.py) with the Agg back-end: the artists drawn
# are the trajectory, its covariance ellipses from the back-end's marginals,
# the graph's odometry and loop closures as the robust decisions say, and the
# step times in the unit of their median; `import hamal` needs no matplotlib.
import math
import os
import subprocess
import sys

import numpy as np
import pytest

matplotlib = pytest.importorskip("matplotlib")
matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
from matplotlib.patches import Ellipse  # noqa: E402

import hamal  # noqa: E402
from conftest import square_world  # noqa: E402
from hamal import x  # noqa: E402


@pytest.fixture(autouse=True)
def close_figures():
    yield
    plt.close("all")


@pytest.fixture
def solved():
    g, _ = square_world(12)
    b = hamal.backend("cholesky")
    assert hamal.run(g, b).not_ok == 0
    return g, b


def test_trajectory_with_the_backends_covariance_ellipses(solved):
    _, b = solved
    ax = hamal.plot.trajectory(b, every=3)
    (line,) = [a for a in ax.lines if a.get_label() == "trajectory"]
    poses = b.estimate().poses()
    assert np.allclose(line.get_xdata(), poses[:, 0]) and np.allclose(line.get_ydata(), poses[:, 1])
    ellipses = [p for p in ax.patches if isinstance(p, Ellipse)]
    assert len(ellipses) == 5  # poses 0, 3, 6, 9 and the last, 11
    last = ellipses[-1]
    assert np.allclose(last.center, poses[11, :2])
    w = np.linalg.eigvalsh(b.marginal_covariance(x(11))[:2, :2])
    assert math.isclose(last.width, 4 * math.sqrt(w[1]), rel_tol=1e-9)   # 2 sigma each side
    assert math.isclose(last.height, 4 * math.sqrt(w[0]), rel_tol=1e-9)
    assert last.width > ellipses[0].width  # uncertainty grows away from the prior


def test_trajectory_of_values_or_an_array_draws_no_ellipses_unless_given(solved):
    _, b = solved
    est = b.estimate()
    assert not hamal.plot.trajectory(est).patches
    assert not hamal.plot.trajectory(b, covariance=None).patches
    ax = hamal.plot.trajectory(est.poses())
    assert len(ax.lines) == 1 and not ax.patches
    ax = hamal.plot.trajectory(est, covariance={5: np.diag([4.0, 1.0, 0.1])}, every=1)
    (e,) = ax.patches
    assert np.allclose(e.center, est.poses()[5, :2]) and math.isclose(e.width, 8) and math.isclose(e.height, 4)


def collections(ax):
    return {c.get_gid(): c for c in ax.collections if c.get_gid()}


def test_graph_draws_odometry_and_loop_closures_by_decision(solved):
    g, b = solved
    g.add(hamal.between(x(2), x(8), hamal.Pose2(5, 5, 1), np.eye(3)))  # a false loop closure
    est = b.estimate()
    false_index = len(g) - 1
    for rejected in ([false_index], np.arange(len(g)) == false_index, lambda f: f.keys == [x(2), x(8)]):
        ax = hamal.plot.graph(g, b, rejected=rejected)
        c = collections(ax)
        assert set(c) == {"odometry", "accepted", "rejected"}
        assert len(c["odometry"].get_segments()) == 11
        assert len(c["accepted"].get_segments()) == 1  # x11 -> x0
        (seg,) = c["rejected"].get_segments()
        assert np.allclose(seg, [est.poses()[2, :2], est.poses()[8, :2]])
        assert c["rejected"].get_linestyle()[0][1] is not None  # dashed
        labels = [t.get_text() for t in ax.get_legend().get_texts()]
        assert "loop closures (rejected): 1" in labels and "loop closures (accepted): 1" in labels
    ax = hamal.plot.graph(g)  # at the initial values, every loop closure accepted
    assert len(collections(ax)["accepted"].get_segments()) == 2 and "rejected" not in collections(ax)
    with pytest.raises(ValueError, match="one entry per factor"):
        hamal.plot.graph(g, rejected=np.array([True, False]))


def test_graph_draws_landmarks():
    g, _ = square_world(6)
    g.initial = hamal.ThesisProtocol(g).initial_values()
    g.initial.insert(hamal.l(0), [1.0, 2.0])
    g.add(hamal.pose_point(x(1), hamal.l(0), [0.0, 2.0], np.eye(2)))
    ax = hamal.plot.graph(g)
    (dots,) = [c for c in ax.collections if c.get_label() == "landmarks"]
    assert np.allclose(dots.get_offsets(), [[1.0, 2.0]])
    assert len(collections(ax)["landmark"].get_segments()) == 1


def test_step_times_in_the_unit_of_the_median(solved):
    g, _ = solved
    runs = [hamal.run(g, "cholesky"), hamal.run(g, "aprilsam")]
    ax = hamal.plot.step_times(runs)
    assert [line.get_label() for line in ax.lines] == ["cholesky", "aprilsam"]
    median = np.median(np.concatenate([r.seconds for r in runs]))
    unit, scale = ("us", 1e6) if median < 1e-3 else ("ms", 1e3) if median < 1 else ("s", 1)
    assert ax.get_ylabel() == f"update time ({unit})" and ax.get_yscale() == "log"
    assert np.allclose(ax.lines[1].get_ydata(), runs[1].seconds * scale)


def test_import_hamal_does_not_need_matplotlib(tmp_path):
    blocker = ("import sys\n"
               "class Block:\n"
               "    def find_spec(self, name, path=None, target=None):\n"
               "        if name.split('.')[0] == 'matplotlib': raise ImportError('blocked')\n"
               "sys.meta_path.insert(0, Block())\n"
               "import hamal\n"
               "print(len(hamal.Values.from_numpy([[0, 0, 0]])), 'matplotlib' in sys.modules)\n"
               "try:\n"
               "    hamal.plot\n"
               "except ImportError as e:\n"
               "    print('plot:', e)\n")
    out = subprocess.run([sys.executable, "-c", blocker], capture_output=True, text=True, check=True,
                         env={**os.environ}).stdout.splitlines()
    assert out == ["1 False", "plot: blocked"]


def test_a_backend_without_marginals_draws_the_line_alone():
    path = os.environ.get("HAMAL_EXAMPLE_PLUGIN")
    if not path or not os.path.isfile(path):
        pytest.skip("HAMAL_EXAMPLE_PLUGIN (build/plugins/libhamal_example_plugin.so) not given")
    if not any(b["name"] == "dense-gauss-newton" for b in hamal.list_backends()):
        hamal.load_plugin(path)
    g, _ = square_world()
    b = hamal.backend("dense-gauss-newton")
    b.update(hamal.ThesisProtocol(g).batch())
    ax = hamal.plot.trajectory(b)
    assert len(ax.lines) == 1 and not ax.patches
