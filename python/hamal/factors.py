"""Factor kinds by name, made through the registry (factors/README.md).

Each function writes the kind's g2o line from its arguments, with every
number at full precision (repr of a float reads back to the same double),
and hands it to hamal.parse_factor, so the factor is exactly the one the
g2o reader makes from that line, checked the same way. Arguments are
checked first, so a wrong shape, dtype, a NaN or a matrix that is not
symmetric positive definite is a hamal.Error naming the argument.

A plugin's kind is made the same way by its tag: factor("EDGE_SE2_CAUCHY",
x(0), x(1), Pose2(1, 0, 0), information), or with parse_factor(line).
"""

import numpy as np

from ._hamal import Error, Factor, Key, Pose2, parse_factor


def _id(value, name, kind):
    if isinstance(value, Key):
        if value.kind != kind:
            raise Error(f"{name}: expected a key of kind '{kind}', got {value!r}")
        return str(value.index)
    if isinstance(value, (int, np.integer)) and not isinstance(value, bool) and 0 <= value < 2**56:
        return str(int(value))
    raise Error(f"{name}: expected hamal.{kind}(i) or an integer id in [0, 2**56), got {value!r}")


def _array(value, name, shape):
    if isinstance(value, Pose2):
        value = value.vector()
    try:
        a = np.asarray(value)
    except Exception as e:  # ragged lists and the like
        raise Error(f"{name}: not an array of numbers ({e})") from None
    if a.dtype.kind not in "fiu":
        raise Error(f"{name}: expected real numbers (a float or integer dtype), got dtype {a.dtype}")
    if a.shape != shape:
        raise Error(f"{name}: expected shape {shape}, got {a.shape}")
    a = a.astype(np.float64)
    if not np.all(np.isfinite(a)):
        raise Error(f"{name}: has non-finite entries: {a.tolist()}")
    return a


def _number(value, name):
    return _array(value, name, ())


def _information(value, name, n):
    m = _array(value, name, (n, n))
    scale = max(1.0, float(np.max(np.abs(m))))
    if np.max(np.abs(m - m.T)) > 1e-9 * scale:
        raise Error(f"{name}: the information matrix is not symmetric: {m.tolist()}")
    try:
        np.linalg.cholesky(m)
    except np.linalg.LinAlgError:
        raise Error(f"{name}: the information matrix is not positive definite: {m.tolist()}") from None
    return m


def _fields(*arrays):
    return " ".join(repr(float(v)) for a in arrays for v in np.ravel(a))


def _upper(m):
    return m[np.triu_indices(m.shape[0])]


def _make(tag, *fields):
    return parse_factor(" ".join([tag, *fields]), "g2o", "<" + tag + ">")


def between(a, b, measurement, information):
    """Pose b seen from pose a (a^-1 b: x, y in m, theta in rad; a Pose2 or a 3-vector)
    with its 3 x 3 information (1/m^2, 1/rad^2; symmetric positive definite), g2o EDGE_SE2."""
    return _make("EDGE_SE2", _id(a, "a", "x"), _id(b, "b", "x"),
                 _fields(_array(measurement, "measurement", (3,)),
                         _upper(_information(information, "information", 3))))


def prior(key, pose, information):
    """A prior on a pose (x, y in m, theta in rad) with its 3 x 3 information (g2o EDGE_SE2_PRIOR)."""
    return _make("EDGE_SE2_PRIOR", _id(key, "key", "x"),
                 _fields(_array(pose, "pose", (3,)), _upper(_information(information, "information", 3))))


def position(key, xy, information):
    """A GPS position [x, y] (m) of a pose in the global frame, 2 x 2 information (1/m^2),
    EDGE_SE2_POSITION."""
    return _make("EDGE_SE2_POSITION", _id(key, "key", "x"),
                 _fields(_array(xy, "xy", (2,)), _upper(_information(information, "information", 2))))


def pose_point(pose, landmark, xy, information):
    """A landmark's position [x, y] (m) seen in the pose's frame, 2 x 2 information (1/m^2),
    g2o EDGE_SE2_XY."""
    return _make("EDGE_SE2_XY", _id(pose, "pose", "x"), _id(landmark, "landmark", "l"),
                 _fields(_array(xy, "xy", (2,)), _upper(_information(information, "information", 2))))


def range_bearing(pose, landmark, range_, bearing, information):
    """Range (m) and bearing (rad, from the pose's x axis) from a pose to a landmark,
    2 x 2 information over (range, bearing), EDGE_SE2_RANGE_BEARING."""
    return _make("EDGE_SE2_RANGE_BEARING", _id(pose, "pose", "x"), _id(landmark, "landmark", "l"),
                 _fields(_number(range_, "range"), _number(bearing, "bearing"),
                         _upper(_information(information, "information", 2))))


def landmark_prior(landmark, xy, information):
    """A prior on a landmark's position [x, y] (m), 2 x 2 information (1/m^2), g2o EDGE_XY_PRIOR."""
    return _make("EDGE_XY_PRIOR", _id(landmark, "landmark", "l"),
                 _fields(_array(xy, "xy", (2,)), _upper(_information(information, "information", 2))))


def l2g(pose, map_node, map_pose, measurement, information):
    """A scan match of a pose against a prior-map node of known pose (EDGE_SE2_L2G,
    thesis eq. 5.2): `measurement` is the map node seen from the pose."""
    return _make("EDGE_SE2_L2G", _id(pose, "pose", "x"), _id(map_node, "map_node", "x"),
                 _fields(_array(map_pose, "map_pose", (3,)), _array(measurement, "measurement", (3,)),
                         _upper(_information(information, "information", 3))))


def max_mixture(nominal, null_weight, null_scale):
    """`nominal` or a null hypothesis of weight null_weight and information scaled by
    null_scale (EDGE_MAXMIX; Olson & Agarwal 2012)."""
    if not isinstance(nominal, Factor):
        raise Error(f"nominal: expected a hamal.Factor, got {type(nominal).__name__}")
    return _make("EDGE_MAXMIX", _fields(_number(null_weight, "null_weight"), _number(null_scale, "null_scale")),
                 nominal.line())


FACTOR_KINDS = {
    "between": between, "prior": prior, "position": position, "pose_point": pose_point,
    "range_bearing": range_bearing, "landmark_prior": landmark_prior, "l2g": l2g,
    "max_mixture": max_mixture,
}


def factor(kind, *args, format="g2o"):
    """A factor by kind name ("between", ..., see FACTOR_KINDS) or by any tag the
    registry holds for `format` (a plugin's too). With a tag, the arguments are the
    line's fields in order: keys and numbers as they are, a pose or vector as its
    entries, a square matrix as its upper triangle row-major (g2o's information order)."""
    if kind in FACTOR_KINDS:
        return FACTOR_KINDS[kind](*args)
    fields = []
    for i, a in enumerate(args):
        name = f"field {i}"
        if isinstance(a, Key):
            fields.append(str(a.index))
        elif isinstance(a, (int, np.integer)) and not isinstance(a, bool):
            fields.append(str(int(a)))
        elif isinstance(a, str):
            fields.append(a)
        else:
            arr = np.asarray(a.vector() if isinstance(a, Pose2) else a)
            if arr.ndim == 2:
                arr = _upper(_information(arr, name, arr.shape[0]))
            else:
                arr = _array(arr, name, arr.shape)
            fields.append(_fields(arr))
    return parse_factor(" ".join([kind, *fields]), format, "<" + kind + ">")
