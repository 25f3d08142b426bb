"""hamal: factor-graph back-ends for 2D SLAM and localization, from Python.

The compiled part (_hamal) binds hamal's C++ library; this package adds the
factor kinds by name (factors.py), a run loop with the bench's timing and
chi2 (run.py) and where the public datasets are (data.py).
See python/README.md.
"""

# The project's VERSION (CMakeLists.txt), written here by python/CMakeLists.txt.
from ._version import __version__  # noqa: F401
from ._hamal import (  # noqa: F401
    Backend, Error, Factor, Graph, JacobianCheckResult, Key, LagoResult, PhaseTimes,
    Point2, Pose2, PythonFactor, STATUS_CODES, Status, Step, StepIterator, StepSource,
    ThesisProtocol, TrajectoryError, UPDATE_KINDS, UpdateResult, Values, absolute_trajectory_error, backend,
    check_jacobians, chi2, describe_backends, describe_factors, g2o_text, l, lago,
    list_backends, list_factors, load_plugin, load_plugins_from_path, parse_factor,
    parse_graph, read_graph, set_between_residual, wrap_angle, write_g2o, x)
from .factors import (  # noqa: F401
    FACTOR_KINDS, between, factor, l2g, landmark_prior, max_mixture, pose_point, position,
    prior, range_bearing)
from .data import data_dir, dataset  # noqa: F401
from .run import Run, compare, format_seconds, run, table, table_html  # noqa: F401

Error.__module__ = __name__  # shown as hamal.Error in tracebacks


def __getattr__(name):
    # hamal.plot is imported on first use: `import hamal` needs no matplotlib.
    if name == "plot":
        import importlib
        return importlib.import_module(".plot", __name__)
    raise AttributeError(f"module 'hamal' has no attribute {name!r}")

# As the executables do: plugins in HAMAL_PLUGIN_PATH's directories are loaded.
load_plugins_from_path()
