# Graphs read and written through the C++ readers and writer: g2o, TORO and
# GTSAM text, with the readers' file:line messages.
import numpy as np
import pytest

import hamal
from conftest import dataset_or_skip

G2O = """VERTEX_SE2 0 0 0 0
VERTEX_SE2 1 1 0 0
VERTEX_XY 5 1 1
FIX 0
EDGE_SE2 0 1 1 0 0 100 0 0 100 0 400
EDGE_SE2_XY 1 5 0 1 10 0 10
"""


def test_g2o_text_reads_with_vertices_fixes_and_landmarks():
    g = hamal.parse_graph(G2O, "small.g2o")
    assert len(g) == 2 and g.source == "small.g2o"
    assert g.initial.pose(hamal.x(1)) == hamal.Pose2(1, 0, 0)
    assert np.array_equal(g.initial.point(hamal.l(5)), [1, 1])
    assert g.fixed == {hamal.x(0)}
    assert [f.tag for f in g.factors] == ["EDGE_SE2", "EDGE_SE2_XY"]
    assert g.factors[0].keys == [hamal.x(0), hamal.x(1)]
    assert set(g.keys()) == {hamal.x(0), hamal.x(1), hamal.l(5)}


def test_write_and_read_back_is_the_same_graph(tmp_path):
    g = hamal.parse_graph(G2O, "small.g2o")
    path = str(tmp_path / "out.g2o")
    g.write(path)
    back = hamal.read_graph(path)
    assert [f.line() for f in back.factors] == [f.line() for f in g.factors]
    assert np.array_equal(back.initial.poses(), g.initial.poses())
    assert back.fixed == g.fixed
    assert hamal.g2o_text(g.initial, g.factors, g.fixed) == open(path).read()


def test_toro_and_gtsam_conventions():
    toro = hamal.parse_graph("EDGE2 0 1 1 0 0 10 1 20 30 2 3\n", "a.toro", "toro")
    gtsam = hamal.parse_graph("EDGE2 0 1 1 0 0 0.1 0 0 0.05 0 0.01\n", "a.txt", "gtsam")
    # TORO: I11 I12 I22 I33 I13 I23 -> written as g2o's I11 I12 I13 I22 I23 I33.
    assert toro.factors[0].line().split()[6:] == ["10", "1", "2", "20", "3", "30"]
    # GTSAM: a covariance, written as its inverse.
    assert [float(v) for v in gtsam.factors[0].line().split()[6:]] == pytest.approx([10, 0, 0, 20, 0, 100])
    with pytest.raises(hamal.Error, match="ambiguous|format"):
        hamal.parse_graph("EDGE2 0 1 1 0 0 10 1 20 30 2 3\n", "a.txt", "auto")


def test_reader_errors_name_file_line_and_reason(tmp_path):
    with pytest.raises(hamal.Error, match=r"^bad\.g2o:2: .*I33 is 'nan'"):
        hamal.parse_graph("VERTEX_SE2 0 0 0 0\nEDGE_SE2 0 0 1 0 0 1 0 0 1 0 nan\n", "bad.g2o")
    with pytest.raises(hamal.Error, match=r"^bad\.g2o:1: .*not symmetric positive definite|^bad\.g2o:1: "):
        hamal.parse_graph("EDGE_SE2 0 1 1 0 0 1 0 0 1 0 -1\n", "bad.g2o")
    with pytest.raises(hamal.Error, match=r"^bad\.g2o:1: .*EDGE_FOO"):
        hamal.parse_graph("EDGE_FOO 0 1\n", "bad.g2o")
    with pytest.raises(ValueError):  # hamal.Error is a ValueError
        hamal.read_graph(str(tmp_path / "missing.g2o"))
    with pytest.raises(hamal.Error, match="unknown file format 'xml'"):
        hamal.read_graph("x.g2o", "xml")


def test_public_datasets_in_their_three_formats():
    m3500 = hamal.read_graph(dataset_or_skip("M3500.toro"))
    assert len(m3500) == 5453 and len(m3500.initial) == 3500
    intel = hamal.read_graph(dataset_or_skip("intel.g2o"))
    assert len(intel) > 1000
    victoria = hamal.read_graph(dataset_or_skip("victoria_park.txt"), "gtsam")
    assert any(f.tag == "EDGE_SE2_XY" for f in victoria.factors)


def test_python_factors_are_refused_by_writers_before_writing(tmp_path):
    f = hamal.PythonFactor([hamal.x(0)], 1, lambda x: (np.zeros(1), [np.zeros((1, 3))]))
    v = hamal.Values()
    v.insert(hamal.x(0), hamal.Pose2())
    path = tmp_path / "out.g2o"
    with pytest.raises(hamal.Error, match="entry 0 .*written in Python"):
        hamal.write_g2o(str(path), v, [f])
    assert not path.exists()


def test_pose_graph_written_as_toro_and_gtsam_reads_back(tmp_path):
    g = hamal.parse_graph(
        "VERTEX_SE2 0 0 0 0\nVERTEX_SE2 1 1 0 0.1\nVERTEX_SE2 2 2 0.5 0.2\n"
        "EDGE_SE2 0 1 1 0 0.1 10 0 0 10 0 20\nEDGE_SE2 1 2 1 0.5 0.1 10 1 0 10 0 20\n"
        "EDGE_SE2 0 2 2 0.4 0.2 5 0 0 5 0 9\n", "g.g2o")
    for fmt, name in (("toro", "g.toro"), ("gtsam", "g.txt")):
        path = tmp_path / name
        g.write(str(path), format=fmt)
        back = hamal.read_graph(str(path), fmt)
        assert len(back.factors) == len(g.factors)
        assert abs(hamal.chi2(back.factors, g.initial) - hamal.chi2(g.factors, g.initial)) < 1e-9
    with_landmark = hamal.parse_graph(
        "VERTEX_SE2 0 0 0 0\nVERTEX_XY 1 1 0\nEDGE_SE2_XY 0 1 1 0 10 0 10\n", "l.g2o")
    with pytest.raises(hamal.Error, match="not a pose"):
        with_landmark.write(str(tmp_path / "l.toro"), format="toro")
    assert not (tmp_path / "l.toro").exists()
