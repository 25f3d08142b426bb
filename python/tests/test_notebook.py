# python/examples/tour.ipynb runs: its code cells are executed in order in one
# namespace with matplotlib's Agg back-end, as plain Python (no Jupyter kernel),
# and it is kept without outputs so the repository holds only its source.
import json
import os

import pytest

NOTEBOOK = os.path.join(os.path.dirname(__file__), "..", "examples", "tour.ipynb")


def code_cells(path):
    with open(path) as f:
        nb = json.load(f)
    assert nb["nbformat"] == 4
    return [c for c in nb["cells"] if c["cell_type"] == "code"]


def test_the_tour_notebook_runs(tmp_path, monkeypatch):
    matplotlib = pytest.importorskip("matplotlib")
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    cells = code_cells(NOTEBOOK)
    assert len(cells) >= 5
    for c in cells:
        assert c["outputs"] == [] and c["execution_count"] is None, "commit the notebook without outputs"
    monkeypatch.chdir(tmp_path)  # whatever it writes stays out of the checkout
    namespace = {"__name__": "__main__"}
    try:
        for i, c in enumerate(cells):
            source = "".join(c["source"])
            assert not any(line.lstrip().startswith(("%", "!")) for line in source.splitlines()), \
                f"cell {i}: magics need a kernel"
            exec(compile(source, f"{NOTEBOOK}[code cell {i}]", "exec"), namespace)
        assert namespace["cov"].shape == (3, 3)
        fig = namespace["fig"]
        trajectory_ax, graph_ax, times_ax = fig.axes[:3]
        assert len(trajectory_ax.patches) >= 12  # the ellipses
        assert {c.get_gid() for c in graph_ax.collections} >= {"odometry", "accepted", "rejected"}
        assert len(times_ax.lines) == 2
    finally:
        plt.close("all")
