"""The thesis' between factor (factors/between_factor.h) written in Python, as
a user would prototype a factor: residual, analytic Jacobians and the guess
the thesis protocol initialises a pose from. Its C++ twin is
hamal.between(a, b, z, information); the tests compare the two to 1e-9 and
python/benchmarks/python_factor_cost.py times one against the other.

    PYTHONPATH=build/python:python/examples python3
    >>> import hamal, numpy as np, python_between
    >>> f = python_between.between(hamal.x(0), hamal.x(1), [1, 0, 0], np.eye(3))
    >>> hamal.check_jacobians(f).ok
    True
"""

import math

import numpy as np

import hamal


def between_function(z, information, counter=None):
    """The callable: whitened e = U [R(th_a)^T (t_b - t_a) - z_t ; wrap(th_b - th_a - z_th)],
    U^T U = information, and its Jacobians. `counter` (a one-element list) counts calls."""
    u = np.linalg.cholesky(information).T
    z = np.asarray(z, dtype=float)

    def f(params):
        if counter is not None:
            counter[0] += 1
        pa, pb = params
        c, s = math.cos(pa[2]), math.sin(pa[2])
        rt = np.array([[c, s], [-s, c]])
        d = pb[:2] - pa[:2]
        e = np.empty(3)
        e[:2] = rt @ d - z[:2]
        e[2] = hamal.wrap_angle(pb[2] - pa[2] - z[2])
        ja = np.zeros((3, 3))
        ja[:2, :2] = -rt
        ja[:2, 2] = np.array([[-s, c], [-c, -s]]) @ d
        ja[2, 2] = -1
        jb = np.zeros((3, 3))
        jb[:2, :2] = rt
        jb[2, 2] = 1
        return u @ e, [u @ ja, u @ jb]

    return f


def between(a, b, z, information, counter=None):
    """A hamal.PythonFactor: pose b seen from pose a."""
    zp = hamal.Pose2(np.asarray(z, dtype=float))

    def predict(unknown, known):  # as BetweenFactor::predict: b = a z, a = b z^-1
        if unknown == b and a in known:
            return known.pose(a).compose(zp)
        if unknown == a and b in known:
            return known.pose(b).compose(zp.inverse())
        return None

    return hamal.PythonFactor([a, b], 3, between_function(z, information, counter),
                              name=f"python_between({a}, {b})", predict=predict)
