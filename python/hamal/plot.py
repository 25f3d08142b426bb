"""hamal.plot: matplotlib figures of an estimate, a graph and a run
(python/README.md, "Plots"). matplotlib is imported here only, on first use
of hamal.plot, so `import hamal` does not need it.

Each function draws into `ax` (a new figure's axes when None) and returns
the axes; the artists carry labels ("trajectory", "covariance", "odometry",
"loop closures (accepted)", "loop closures (rejected)", "landmarks", a run's
spec) so a caller or a test can find them.
"""

import math

import matplotlib.pyplot as plt
import numpy as np
from matplotlib.collections import LineCollection
from matplotlib.patches import Ellipse

from ._hamal import Backend, Graph, ThesisProtocol, Values

# Ellipses drawn by default: about this many along a trajectory.
DEFAULT_ELLIPSES = 25


def _axes(ax):
    if ax is None:
        _, ax = plt.subplots()
    return ax


def _estimate(source):
    if isinstance(source, Backend):
        return source.estimate()
    if isinstance(source, Values):
        return source
    raise TypeError(f"expected a hamal.Values or a hamal.Backend, got {type(source).__name__}")


def covariance_ellipse(mean, covariance, sigma=2.0, **kwargs):
    """The `sigma`-sigma ellipse (an Ellipse patch) of a 2 x 2 covariance (m^2) around
    `mean` [x, y] (m): axes 2 sigma sqrt(eigenvalue), along the eigenvectors."""
    cov = np.asarray(covariance, dtype=float)[:2, :2]
    w, v = np.linalg.eigh(0.5 * (cov + cov.T))
    w = np.maximum(w, 0.0)
    angle = math.degrees(math.atan2(v[1, 1], v[0, 1]))
    return Ellipse(tuple(np.asarray(mean, dtype=float)[:2]), 2 * sigma * math.sqrt(w[1]),
                   2 * sigma * math.sqrt(w[0]), angle=angle, **kwargs)


def trajectory(source, ax=None, covariance="auto", every=None, sigma=2.0, label="trajectory",
               color=None):
    """The poses x(i) of `source` (a hamal.Values, a hamal.Backend, or an N x 3 array of
    x, y, theta) as a line in metres, with `sigma`-sigma position ellipses at every
    `every`-th pose (default: about DEFAULT_ELLIPSES of them, the last pose always).

    covariance: "auto" draws ellipses when `source` is a back-end with
    marginal_covariance (cholesky, ceres, aprilsam), None draws none, or a mapping
    pose id -> 3 x 3 covariance (x, y in the world frame) draws those given."""
    ax = _axes(ax)
    ids = None
    if isinstance(source, (Values, Backend)):
        values = _estimate(source)
        poses, ids = values.poses(), values.pose_ids()
    else:
        poses = np.asarray(source, dtype=float).reshape(-1, 3)
    (line,) = ax.plot(poses[:, 0], poses[:, 1], lw=1.0, color=color, label=label)
    covariances = {}
    if ids is not None and len(ids):
        if every is None:
            every = max(1, len(ids) // DEFAULT_ELLIPSES)
        chosen = sorted(set(range(0, len(ids), every)) | {len(ids) - 1})
        if isinstance(covariance, str):
            if covariance != "auto":
                raise ValueError(f"covariance: expected 'auto', None or a mapping, got {covariance!r}")
            if isinstance(source, Backend):
                from ._hamal import x
                try:
                    covariances = {int(ids[i]): source.marginal_covariance(x(int(ids[i]))) for i in chosen}
                except TypeError:  # a back-end without marginal covariances: the line alone
                    covariances = {}
        elif covariance is not None:
            wanted = {int(ids[i]) for i in chosen}
            covariances = {int(k): c for k, c in covariance.items() if int(k) in wanted}
    row = {int(i): r for r, i in enumerate(ids)} if ids is not None else {}
    for i, cov in covariances.items():
        ax.add_patch(covariance_ellipse(poses[row[i], :2], cov, sigma, fill=False, lw=0.8,
                                        color=line.get_color(), label="covariance"))
    ax.set_aspect("equal", adjustable="datalim")
    ax.set_xlabel("x (m)")
    ax.set_ylabel("y (m)")
    return ax


def _rejected_set(graph, rejected):
    n = len(graph)
    if rejected is None:
        return set()
    if callable(rejected):
        return {i for i in range(n) if rejected(graph[i])}
    r = np.asarray(list(rejected) if not isinstance(rejected, np.ndarray) else rejected)
    if r.dtype == bool:
        if r.shape != (n,):
            raise ValueError(f"rejected: a boolean mask needs one entry per factor ({n}), got {r.shape}")
        return set(np.flatnonzero(r).tolist())
    return {int(i) for i in r}


def graph(g, values=None, ax=None, rejected=None, odometry_color="0.6",
          accepted_color="tab:green", rejected_color="tab:red"):
    """The pose graph `g` drawn at `values` (a Values or Backend; default g.initial, or
    the thesis protocol's odometry guesses when the graph has none):
    odometry (factors between x(i) and x(i+1)) in grey, loop closures (any other factor
    between two poses) in green when accepted and dashed red when rejected, landmarks
    as dots with their pose-landmark factors faint.

    rejected: the robust decisions, as factor indices into g.factors, a boolean mask
    (one per factor) or a function factor -> bool; None: every loop closure accepted."""
    if not isinstance(g, Graph):
        raise TypeError(f"expected a hamal.Graph, got {type(g).__name__}")
    ax = _axes(ax)
    if values is not None:
        est = _estimate(values)
    else:
        est = g.initial if len(g.initial) else ThesisProtocol(g).initial_values()
    out = _rejected_set(g, rejected)
    segments = {"odometry": [], "accepted": [], "rejected": [], "landmark": []}
    for i, f in enumerate(g.factors):
        keys = [k for k in f.keys if k in est]
        if len(keys) != 2:
            continue
        a, b = keys
        xy = [np.asarray(est[k])[:2] for k in (a, b)]
        if a.kind == "x" and b.kind == "x":
            if abs(int(a.index) - int(b.index)) == 1 and i not in out:
                segments["odometry"].append(xy)
            else:
                segments["rejected" if i in out else "accepted"].append(xy)
        else:
            segments["landmark"].append(xy)
    style = {
        "odometry": dict(colors=odometry_color, linewidths=0.8, label="odometry"),
        "accepted": dict(colors=accepted_color, linewidths=0.8,
                         label=f"loop closures (accepted): {len(segments['accepted'])}"),
        "rejected": dict(colors=rejected_color, linewidths=0.8, linestyles="dashed",
                         label=f"loop closures (rejected): {len(segments['rejected'])}"),
        "landmark": dict(colors="0.85", linewidths=0.5, label="landmark observations"),
    }
    for name in ("landmark", "odometry", "accepted", "rejected"):
        if segments[name]:
            collection = LineCollection(segments[name], **style[name])
            collection.set_gid(name)
            ax.add_collection(collection)
    landmarks = est.landmarks()
    if len(landmarks):
        ax.scatter(landmarks[:, 0], landmarks[:, 1], s=8, color="tab:blue", label="landmarks", zorder=3)
    ax.autoscale_view()
    ax.set_aspect("equal", adjustable="datalim")
    ax.set_xlabel("x (m)")
    ax.set_ylabel("y (m)")
    ax.legend(loc="best", fontsize="small")
    return ax


_UNITS = ((1.0, "s"), (1e-3, "ms"), (1e-6, "us"))


def step_times(runs, ax=None, log=True):
    """The time of each update against its step, one line per hamal.Run (or a list of
    them), in the unit (s, ms or us) the median update is at least 1 of; log scale
    unless log=False."""
    if not isinstance(runs, (list, tuple)):
        runs = [runs]
    ax = _axes(ax)
    all_seconds = np.concatenate([np.asarray(r.seconds, dtype=float) for r in runs] or [np.zeros(0)])
    median = float(np.median(all_seconds)) if all_seconds.size else 1.0
    scale, unit = next(((s, u) for s, u in _UNITS if median >= s), _UNITS[-1])
    for r in runs:
        y = np.asarray(r.seconds, dtype=float) / scale
        ax.plot(np.arange(len(y)), y, lw=0.6, label=r.spec)
    if log:
        ax.set_yscale("log")
    ax.set_xlabel("step")
    ax.set_ylabel(f"update time ({unit})")
    ax.legend(loc="best", fontsize="small")
    return ax
