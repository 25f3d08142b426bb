# The examples of python/examples run and say what their READMEs claim.
import os
import sys

import numpy as np
import pytest

sys.path.insert(0, os.path.join(os.path.dirname(__file__), "..", "examples"))

import m3500_comparison  # noqa: E402
import range_only_factor  # noqa: E402
from conftest import dataset_or_skip  # noqa: E402


def test_range_only_beacons_in_python_improve_on_odometry_and_the_survey():
    r = range_only_factor.solve("aprilsam", poses=150)
    assert r["ate"].translation_rmse < r["ate_dead_reckoning"].translation_rmse / 2
    assert np.all(r["beacon_error"] < r["surveyed_error"])


def test_m3500_comparison_table_and_plot(tmp_path):
    path = dataset_or_skip("M3500.toro")
    runs = m3500_comparison.compare(path, ["aprilsam", "cholesky"], max_steps=200)
    text = m3500_comparison.table(runs)
    lines = text.splitlines()
    assert lines[0].split()[:2] == ["back-end", "steps"] and len(lines) == 4
    assert lines[2].startswith("aprilsam") and " 200 " in lines[2]
    pytest.importorskip("matplotlib")
    out = m3500_comparison.plot(runs, str(tmp_path / "steps.png"))
    assert os.path.getsize(out) > 1000
