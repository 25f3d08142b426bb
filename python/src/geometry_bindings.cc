// Key, Pose2, Point2 and Values in Python (core/key.h, core/pose2.h,
// core/values.h), named as GTSAM's wrapper names them: x(i) and l(i) for
// keys, a Point2 is a numpy array of 2. Values convert to and from numpy in
// one pass in C++ (an N x 3 array of poses, an M x 2 array of landmarks,
// each with its ids), so a 10^5-pose estimate needs no Python loop.
#include <pybind11/eigen.h>
#include <pybind11/numpy.h>
#include <pybind11/operators.h>
#include <pybind11/stl.h>

#include <algorithm>
#include <cmath>
#include <functional>
#include <sstream>

#include "bindings.h"
#include "core/error.h"
#include "core/key.h"
#include "core/pose2.h"
#include "core/values.h"
#include "numpy_arguments.h"

namespace py = pybind11;

namespace hamal::python {

namespace {

Pose2 checkedPose(double x, double y, double theta) {
  if (!std::isfinite(x) || !std::isfinite(y) || !std::isfinite(theta)) {
    std::ostringstream os;
    os << "Pose2: (" << x << ", " << y << ", " << theta << ") is not finite";
    throw Error(os.str());
  }
  return {x, y, theta};
}

// Key(kind, index) checked as the constructor checks it: Key itself masks an
// index beyond its 56 bits, which would name another variable.
Key checkedKey(const std::string& kind, std::uint64_t index) {
  if (kind.size() != 1) throw Error("Key: kind must be one letter, got '" + kind + "'");
  if (index > Key::kMaxIndex)
    throw Error("Key: index " + std::to_string(index) + " is too large (at most 2**" +
                std::to_string(Key::kIndexBits) + " - 1)");
  return Key(kind[0], index);
}

// The ids of an array: integer dtypes are read as integers (exact to 2**64),
// floats only when integral and below 2**53 (beyond it a float names more
// than one id).
std::vector<std::uint64_t> idArray(py::handle ids, long n) {
  const auto id = numericArray(ids, "ids", n, 0);  // shape and dtype checked
  const py::array raw = py::array::ensure(ids);
  const char kind = raw.dtype().kind();
  std::vector<std::uint64_t> out(n);
  if (kind == 'u' || kind == 'i') {
    auto entryError = [](long i) {
      return Error("ids: entry " + std::to_string(i) +
                   " is not a non-negative integer id below 2**" + std::to_string(Key::kIndexBits));
    };
    if (kind == 'u') {
      const auto a = py::array_t<std::uint64_t, py::array::forcecast>::ensure(raw);
      for (long i = 0; i < n; ++i)
        if ((out[i] = a.at(i)) > Key::kMaxIndex) throw entryError(i);
    } else {
      const auto a = py::array_t<std::int64_t, py::array::forcecast>::ensure(raw);
      for (long i = 0; i < n; ++i) {
        if (a.at(i) < 0 || std::uint64_t(a.at(i)) > Key::kMaxIndex) throw entryError(i);
        out[i] = std::uint64_t(a.at(i));
      }
    }
    return out;
  }
  for (long i = 0; i < n; ++i) {
    const double v = id.at(i);
    if (v < 0 || v != std::floor(v) || v >= 9007199254740992.0)  // 2**53
      throw Error("ids: entry " + std::to_string(i) +
                  " is not a non-negative integer id (a float id must be below 2**53; give "
                  "integer ids beyond)");
    out[i] = static_cast<std::uint64_t>(v);
  }
  return out;
}

Point2 pointArgument(py::handle obj, const std::string& name) {
  const auto a = numericArray(obj, name, 2, 0);
  return {a.at(0), a.at(1)};
}

// Inserts (or sets) a Pose2 or a point-like value.
void put(Values& values, Key key, py::handle value, bool overwrite) {
  if (py::isinstance<Pose2>(value)) {
    const Pose2 p = value.cast<Pose2>();
    overwrite ? values.set(key, p) : values.insert(key, p);
  } else {
    const Point2 p = pointArgument(value, "value of " + key.str());
    overwrite ? values.set(key, p) : values.insert(key, p);
  }
}

py::array_t<std::uint64_t> indexArray(const std::vector<Key>& keys) {
  py::array_t<std::uint64_t> out(static_cast<py::ssize_t>(keys.size()));
  auto* p = out.mutable_data();
  for (std::size_t i = 0; i < keys.size(); ++i) p[i] = keys[i].index();
  return out;
}

// The keys of one variable type and kind, sorted by index.
std::vector<Key> keysOf(const Values& values, VariableType type, char kind) {
  std::vector<Key> keys;
  for (const auto& [k, e] : values)
    if (e.type == type && k.kind() == kind) keys.push_back(k);
  std::sort(keys.begin(), keys.end());
  return keys;
}

py::array_t<double> blockArray(const Values& values, const std::vector<Key>& keys, int dim) {
  py::array_t<double> out({static_cast<py::ssize_t>(keys.size()), static_cast<py::ssize_t>(dim)});
  double* p = out.mutable_data();
  for (std::size_t i = 0; i < keys.size(); ++i) {
    const double* d = values.data(keys[i]);
    for (int c = 0; c < dim; ++c) p[i * dim + c] = d[c];
  }
  return out;
}

// Inserts rows of `array` under kind+ids; checks everything before inserting
// anything, so a bad row leaves `values` as it was.
void insertBlock(Values& values, char kind, py::handle ids, py::handle array, int dim,
                 const char* what, bool overwrite) {
  const auto a = numericArray(array, what, -1, dim);
  const long n = a.shape(0);
  const std::vector<std::uint64_t> id = idArray(ids, n);
  std::vector<Key> keys(n);
  for (long i = 0; i < n; ++i) {
    keys[i] = Key(kind, id[i]);
    if (!overwrite && values.contains(keys[i]))
      throw Error("ids: " + keys[i].str() + " is already in the Values");
  }
  std::vector<Key> sorted = keys;
  std::sort(sorted.begin(), sorted.end());
  if (std::adjacent_find(sorted.begin(), sorted.end()) != sorted.end())
    throw Error("ids: " + std::adjacent_find(sorted.begin(), sorted.end())->str() +
                " appears twice");
  const double* p = a.data();
  for (long i = 0; i < n; ++i) {
    Values::Entry e{dim == 3 ? VariableType::kPose2 : VariableType::kPoint2, {0, 0, 0}};
    for (int c = 0; c < dim; ++c) e.data[c] = p[i * dim + c];
    // An angle already in (-pi, pi] is kept as it is (wrapAngle would round
    // it), so poses from to_numpy() come back bit for bit.
    if (dim == 3 && !(e.data[2] > -M_PI && e.data[2] <= M_PI)) e.data[2] = wrapAngle(e.data[2]);
    overwrite ? values.setEntry(keys[i], e) : values.insertEntry(keys[i], e);
  }
}

}  // namespace

namespace {

// SE(2)'s exponential map at the identity (Sola, Deray and Atchuthan, "A
// micro Lie theory for state estimation in robotics", 2018, example 7):
// the tangent [vx, vy, w] moves along the arc of constant velocity (vx, vy)
// in the body frame and turn rate w for unit time; t = V(w) v with
// V(w) = [sin w, -(1 - cos w); 1 - cos w, sin w] / w. Near w = 0 the
// entries are their Taylor series, so the map is smooth through it.
Eigen::Matrix2d tangentV(double w) {
  double a, b;  // sin(w) / w and (1 - cos(w)) / w
  if (std::abs(w) < 1e-6) {
    a = 1 - w * w / 6;
    b = w / 2 - w * w * w / 24;
  } else {
    a = std::sin(w) / w;
    b = (1 - std::cos(w)) / w;
  }
  Eigen::Matrix2d v;
  v << a, -b, b, a;
  return v;
}

Pose2 se2Exp(py::handle xi_arg) {
  const auto xi = numericArray(xi_arg, "xi", 3, 0);
  const Eigen::Vector2d t = tangentV(xi.at(2)) * Eigen::Vector2d(xi.at(0), xi.at(1));
  return {t.x(), t.y(), wrapAngle(xi.at(2))};
}

// The inverse of se2Exp for the angle in (-pi, pi]: w = theta, v = V(w)^-1 t.
Eigen::Vector3d se2Log(const Pose2& p) {
  const Eigen::Matrix2d V = tangentV(p.theta);  // [a, -b; b, a], its inverse [a, b; -b, a] / det
  const Eigen::Vector2d v = V.transpose() * p.t() / (V(0, 0) * V(0, 0) + V(1, 0) * V(1, 0));
  return {v.x(), v.y(), p.theta};
}

// One point (shape (2,)) or N points (shape (N, 2)) through `map`, in C++.
py::array_t<double> mapPoints(py::handle points, const char* name,
                              const std::function<Point2(const Point2&)>& map) {
  const py::array raw = py::array::ensure(points);
  if (raw && raw.ndim() == 2) {
    const auto a = numericArray(points, name, -1, 2);
    py::array_t<double> out({a.shape(0), py::ssize_t(2)});
    double* o = out.mutable_data();
    const double* p = a.data();
    for (py::ssize_t i = 0; i < a.shape(0); ++i) {
      const Point2 q = map(Point2(p[2 * i], p[2 * i + 1]));
      o[2 * i] = q.x();
      o[2 * i + 1] = q.y();
    }
    return out;
  }
  const Point2 q = map(pointArgument(points, name));
  py::array_t<double> out(2);
  out.mutable_at(0) = q.x();
  out.mutable_at(1) = q.y();
  return out;
}

py::object valueObject(const Values& v, Key k) {
  if (v.type(k) == VariableType::kPose2) return py::cast(v.pose(k));
  return py::cast(Point2(v.point(k)));
}

// Values' pickled state: every entry as (kind letters, indices, types, data),
// in numpy arrays, so a 10^5-variable estimate pickles in one pass.
py::tuple valuesState(const Values& v) {
  const std::vector<Key> keys = v.keys();
  const auto n = static_cast<py::ssize_t>(keys.size());
  std::string kinds;
  py::array_t<std::uint64_t> index(n);
  py::array_t<std::uint8_t> type(n);
  py::array_t<double> data({n, py::ssize_t(3)});
  for (py::ssize_t i = 0; i < n; ++i) {
    const Key k = keys[std::size_t(i)];
    kinds += k.kind();
    index.mutable_at(i) = k.index();
    type.mutable_at(i) = v.type(k) == VariableType::kPose2 ? 0 : 1;
    const double* d = v.data(k);
    const int dim = v.dim(k);
    for (int c = 0; c < 3; ++c) data.mutable_at(i, c) = c < dim ? d[c] : 0.0;
  }
  return py::make_tuple(py::bytes(kinds), index, type, data);
}

Values valuesFromState(const py::tuple& t) {
  if (t.size() != 4) throw Error("Values: state must be (kinds, indices, types, data)");
  const std::string kinds = t[0].cast<std::string>();
  const long n = long(kinds.size());
  const auto index = py::array_t<std::uint64_t, py::array::forcecast>::ensure(t[1]);
  const auto type = py::array_t<std::uint8_t, py::array::forcecast>::ensure(t[2]);
  const auto data = numericArray(t[3], "Values state data", n, 3);
  if (!index || !type || index.ndim() != 1 || type.ndim() != 1 || index.shape(0) != n ||
      type.shape(0) != n)
    throw Error("Values: state arrays do not match the " + std::to_string(n) + " kinds");
  Values v;
  for (long i = 0; i < n; ++i) {
    if (type.at(i) > 1)
      throw Error("Values: state type " + std::to_string(type.at(i)) + " unknown");
    const Key k = checkedKey(std::string(1, kinds[std::size_t(i)]), index.at(i));
    Values::Entry e{type.at(i) == 0 ? VariableType::kPose2 : VariableType::kPoint2,
                    {data.at(i, 0), data.at(i, 1), type.at(i) == 0 ? data.at(i, 2) : 0.0}};
    v.insertEntry(k, e);  // throws for a repeated key
  }
  return v;
}

}  // namespace

// Key, and hamal.x / hamal.l that make the usual ones.
static void bindKey(py::module_& m) {
  py::class_<Key>(m, "Key",
                  "The name of a variable: a kind letter ('x' pose, 'l' landmark) and an index "
                  "below 2**56. Hashable and ordered (by kind, then index); hamal.x(i) and "
                  "hamal.l(j) make the usual ones.")
      .def(py::init(&checkedKey), py::arg("kind"), py::arg("index"),
           "Key(kind, index): kind one letter, index in [0, 2**56); hamal.Error otherwise.")
      .def_property_readonly(
          "kind", [](Key k) { return std::string(1, k.kind()); },
          "str: the kind letter, 'x' a pose, 'l' a landmark (others for plugins' variables).")
      .def_property_readonly("index", &Key::index, "The index within the kind, in [0, 2**56).")
      .def("__str__", &Key::str)
      .def("__repr__",
           [](Key k) {
             const std::string kind(1, k.kind()), index = std::to_string(k.index());
             return k.kind() == kPoseKind || k.kind() == kLandmarkKind
                        ? kind + "(" + index + ")"
                        : "Key('" + kind + "', " + index + ")";
           })
      .def("__hash__", [](Key k) { return std::hash<Key>()(k); })
      .def(py::self == py::self)
      .def(py::self != py::self)
      .def(py::self < py::self)
      .def(py::pickle([](Key k) { return py::make_tuple(std::string(1, k.kind()), k.index()); },
                      [](py::tuple t) {
                        if (t.size() != 2) throw Error("Key: state must be (kind, index)");
                        return checkedKey(t[0].cast<std::string>(), t[1].cast<std::uint64_t>());
                      }));
  m.def(
      "x", [](std::uint64_t i) { return checkedKey("x", i); }, py::arg("index"),
      "The key of pose i (i < 2**56).");
  m.def(
      "l", [](std::uint64_t i) { return checkedKey("l", i); }, py::arg("index"),
      "The key of landmark i (i < 2**56).");
}

// Pose2 (SE(2)), wrap_angle and Point2 (a numpy 2-vector).
static void bindPose2(py::module_& m) {
  py::class_<Pose2>(
      m, "Pose2",
      "A 2D pose (x, y, theta): the robot's frame in the global frame, x and y in metres, theta "
      "in radians, wrapped to (-pi, pi] by the group operations. An element of SE(2): p * q "
      "composes, np.asarray(p) is the float array [x, y, theta], exp/log map the tangent "
      "[vx, vy, w]. A sequence of 3: x, y, theta = p; np.array(list_of_poses) is N x 3.")
      .def(py::init([](double x, double y, double theta) { return checkedPose(x, y, theta); }),
           py::arg("x") = 0.0, py::arg("y") = 0.0, py::arg("theta") = 0.0,
           "Pose2(x=0, y=0, theta=0) in metres and radians; hamal.Error if not finite.")
      .def(py::init([](py::handle v) {
             const auto a = numericArray(v, "Pose2", 3, 0);
             return Pose2(a.at(0), a.at(1), a.at(2));
           }),
           py::arg("vector"), "Pose2([x, y, theta]) from any 3-vector (a numpy array, a list).")
      .def_readonly("x", &Pose2::x, "x of the origin in the global frame (m).")
      .def_readonly("y", &Pose2::y, "y of the origin in the global frame (m).")
      .def_readonly("theta", &Pose2::theta, "Heading (rad): the x axis' angle from the global x.")
      .def_static(
          "identity", []() { return Pose2(); }, "The identity pose (0, 0, 0).")
      .def("compose", &Pose2::compose, py::arg("other"),
           "self * other: `other` (given in this pose's frame) in the global frame.")
      .def("__mul__", &Pose2::compose, py::arg("other"))
      .def("inverse", &Pose2::inverse,
           "The inverse: composed with this pose, it gives the identity.")
      .def("between", &Pose2::between, py::arg("other"),
           "self.inverse() * other: `other` seen from this pose (an odometry measurement).")
      .def_static("exp", &se2Exp, py::arg("xi"),
                  "SE(2)'s exponential map: the pose reached from the identity by the tangent "
                  "xi = [vx, vy, w] (m, m, rad; velocities in the body frame over unit time).")
      .def("log", &se2Log,
           "SE(2)'s logarithm: the tangent [vx, vy, w] that Pose2.exp maps back to this pose, w = "
           "theta "
           "in (-pi, pi].")
      .def(
          "transform_from",
          [](const Pose2& p, py::handle q) {
            return mapPoints(q, "point", [&p](const Point2& a) { return p.transformFrom(a); });
          },
          py::arg("point"),
          "Points in this pose's frame to the global frame: a 2-vector, or an N x 2 array in one "
          "call (m).")
      .def(
          "transform_to",
          [](const Pose2& p, py::handle q) {
            return mapPoints(q, "point", [&p](const Point2& a) { return p.transformTo(a); });
          },
          py::arg("point"),
          "Points in the global frame to this pose's frame: a 2-vector or an N x 2 array (m).")
      .def("translation", &Pose2::t, "A new array [x, y] (m).")
      .def("rotation", &Pose2::R, "The 2 x 2 rotation matrix of theta (a new array).")
      .def(
          "vector", [](const Pose2& p) { return Eigen::Vector3d(p.x, p.y, p.theta); },
          "A new array [x, y, theta], as np.asarray(pose).")
      .def(
          "matrix",
          [](const Pose2& p) {
            Eigen::Matrix3d t = Eigen::Matrix3d::Identity();
            t.topLeftCorner<2, 2>() = p.R();
            t.topRightCorner<2, 1>() = p.t();
            return t;
          },
          "The 3 x 3 homogeneous transform [[R, t], [0, 0, 1]].")
      .def(
          "__array__",
          [](const Pose2& p, py::object dtype, py::object) {
            py::array_t<double> a(3);
            a.mutable_at(0) = p.x;
            a.mutable_at(1) = p.y;
            a.mutable_at(2) = p.theta;
            if (dtype.is_none()) return py::object(a);
            return py::object(a.attr("astype")(dtype));
          },
          py::arg("dtype") = py::none(), py::arg("copy") = py::none())
      .def("__len__", [](const Pose2&) { return 3; })
      .def("__getitem__",
           [](const Pose2& p, long i) {
             if (i < 0) i += 3;
             if (i < 0 || i > 2) throw py::index_error("Pose2 index out of range (x, y, theta)");
             return i == 0 ? p.x : i == 1 ? p.y : p.theta;
           })
      .def("__eq__", [](const Pose2& a,
                        const Pose2& b) { return a.x == b.x && a.y == b.y && a.theta == b.theta; })
      .def("__repr__",
           [](const Pose2& p) {
             std::ostringstream os;
             os.precision(17);
             os << "Pose2(" << p.x << ", " << p.y << ", " << p.theta << ")";
             return os.str();
           })
      .def(py::pickle([](const Pose2& p) { return py::make_tuple(p.x, p.y, p.theta); },
                      [](py::tuple t) {
                        if (t.size() != 3) throw Error("Pose2: state must be (x, y, theta)");
                        return checkedPose(t[0].cast<double>(), t[1].cast<double>(),
                                           t[2].cast<double>());
                      }));
  m.def("wrap_angle", &wrapAngle, py::arg("angle"), "The angle (rad) wrapped to (-pi, pi].");
  m.def(
      "Point2", [](double x, double y) { return Point2(x, y); }, py::arg("x"), py::arg("y"),
      "A 2D point (m): a numpy array of 2 (as in GTSAM's wrapper).");
}

// Values as a mapping Key -> Pose2 or point: construction, access, copies, pickling.
static void bindValuesMapping(py::class_<Values>& values) {
  values.def(py::init<>(), "Empty Values.")
      .def(py::init([](const Values& v) { return Values(v); }), py::arg("other"), "A copy.")
      .def(
          "insert", [](Values& v, Key k, py::handle value) { put(v, k, value, false); },
          py::arg("key"), py::arg("value"),
          "Adds a variable (a Pose2 or a 2-vector); hamal.Error if the key exists.")
      .def(
          "set", [](Values& v, Key k, py::handle value) { put(v, k, value, true); }, py::arg("key"),
          py::arg("value"), "Inserts or overwrites a variable (a Pose2 or a 2-vector).")
      .def("erase", &Values::erase, py::arg("key"), "Removes a variable; hamal.Error if absent.")
      .def("contains", &Values::contains, py::arg("key"), "key in values (GTSAM's spelling).")
      .def("__contains__", &Values::contains)
      .def("__len__", &Values::size)
      .def(
          "__iter__", [](const Values& v) { return py::iter(py::cast(v.keys())); },
          "The keys, sorted by kind then index (a snapshot: changing the Values meanwhile is "
          "safe).")
      .def(
          "size",
          [](const Values& v) {
            warnDeprecated("Values.size() is deprecated: use len(values)");
            return v.size();
          },
          "Deprecated: len(values).")
      .def(
          "empty",
          [](const Values& v) {
            warnDeprecated("Values.empty() is deprecated: use len(values) == 0 (or not values)");
            return v.empty();
          },
          "Deprecated: len(values) == 0.")
      .def("keys", &Values::keys, "A new list of every key, sorted by kind then index.")
      .def(
          "items",
          [](const Values& v) {
            py::list out;
            for (Key k : v.keys()) out.append(py::make_tuple(k, valueObject(v, k)));
            return out;
          },
          "A new list of (key, value) pairs sorted by key: a Pose2 or a point array each.")
      .def("pose", &Values::pose, py::arg("key"), "The Pose2 at `key`; hamal.Error if none.")
      .def("atPose2", &Values::pose, py::arg("key"), "pose(key) (GTSAM's spelling).")
      .def(
          "point", [](const Values& v, Key k) { return Point2(v.point(k)); }, py::arg("key"),
          "The point at `key` as an array [x, y] (m); hamal.Error if none.")
      .def(
          "atPoint2", [](const Values& v, Key k) { return Point2(v.point(k)); }, py::arg("key"),
          "point(key) (GTSAM's spelling).")
      .def("__getitem__", &valueObject)
      .def(
          "type", [](const Values& v, Key k) { return std::string(typeName(v.type(k))); },
          py::arg("key"), "The variable's type: 'Pose2' or 'Point2'.")
      .def("dim", &Values::dim, py::arg("key"),
           "The variable's dimension: 3 for a Pose2, 2 for a point.")
      .def(
          "copy", [](const Values& v) { return Values(v); }, "A copy (O(variables)).")
      .def("__copy__", [](const Values& v) { return Values(v); })
      .def("__deepcopy__", [](const Values& v, py::dict) { return Values(v); })
      .def(py::pickle(&valuesState, &valuesFromState));
}

// Values' arrays: poses and landmarks to and from numpy in one pass.
static void bindValuesArrays(py::class_<Values>& values) {
  values
      .def(
          "poses",
          [](const Values& v) {
            return blockArray(v, keysOf(v, VariableType::kPose2, kPoseKind), 3);
          },
          "The poses x(i) as a new N x 3 array (x, y, theta), sorted by i (pose_ids()).")
      .def(
          "pose_ids",
          [](const Values& v) { return indexArray(keysOf(v, VariableType::kPose2, kPoseKind)); },
          "The i of every pose x(i), sorted: a new uint64 array, the rows of poses().")
      .def(
          "landmarks",
          [](const Values& v) {
            return blockArray(v, keysOf(v, VariableType::kPoint2, kLandmarkKind), 2);
          },
          "The landmarks l(j) as a new M x 2 array, sorted by j (landmark_ids()).")
      .def(
          "landmark_ids",
          [](const Values& v) {
            return indexArray(keysOf(v, VariableType::kPoint2, kLandmarkKind));
          },
          "The j of every landmark l(j), sorted: a new uint64 array, the rows of landmarks().")
      .def(
          "to_numpy",
          [](const Values& v) {
            const auto poses = keysOf(v, VariableType::kPose2, kPoseKind);
            const auto points = keysOf(v, VariableType::kPoint2, kLandmarkKind);
            if (poses.size() + points.size() != v.size())
              for (const auto& [k, e] : v)
                if (!((e.type == VariableType::kPose2 && k.kind() == kPoseKind) ||
                      (e.type == VariableType::kPoint2 && k.kind() == kLandmarkKind)))
                  throw Error("to_numpy: " + k.str() + " (a " + typeName(e.type) +
                              ") is neither a pose x(i) nor a landmark l(j); the arrays "
                              "cannot hold it");
            return py::make_tuple(blockArray(v, poses, 3), blockArray(v, points, 2),
                                  indexArray(poses), indexArray(points));
          },
          "(poses N x 3, landmarks M x 2, pose_ids, landmark_ids): the whole Values as arrays, "
          "so Values.from_numpy of them equals this Values. hamal.Error for a variable other than "
          "a pose x(i) or a landmark l(j).")
      .def(
          "insert_poses",
          [](Values& v, py::handle ids, py::handle poses) {
            insertBlock(v, kPoseKind, ids, poses, 3, "poses", false);
          },
          py::arg("ids"), py::arg("poses"),
          "Adds x(ids[i]) = poses[i] from an N x 3 array; all or nothing.")
      .def(
          "insert_landmarks",
          [](Values& v, py::handle ids, py::handle points) {
            insertBlock(v, kLandmarkKind, ids, points, 2, "landmarks", false);
          },
          py::arg("ids"), py::arg("landmarks"),
          "Adds l(ids[j]) = landmarks[j] from an M x 2 array; all or nothing.")
      .def(
          "set_poses",
          [](Values& v, py::handle ids, py::handle poses) {
            insertBlock(v, kPoseKind, ids, poses, 3, "poses", true);
          },
          py::arg("ids"), py::arg("poses"),
          "Inserts or overwrites x(ids[i]) = poses[i] from an N x 3 array; all or nothing.")
      .def(
          "set_landmarks",
          [](Values& v, py::handle ids, py::handle points) {
            insertBlock(v, kLandmarkKind, ids, points, 2, "landmarks", true);
          },
          py::arg("ids"), py::arg("landmarks"),
          "Inserts or overwrites l(ids[j]) = landmarks[j] from an M x 2 array; all or nothing.")
      .def_static(
          "from_numpy",
          [](py::handle poses, py::object landmarks, py::object pose_ids, py::object landmark_ids) {
            Values v;
            const auto p = numericArray(poses, "poses", -1, 3);
            py::object pid =
                pose_ids.is_none()
                    ? py::object(py::module_::import("numpy").attr("arange")(p.shape(0)))
                    : pose_ids;
            insertBlock(v, kPoseKind, pid, p, 3, "poses", false);
            if (!landmarks.is_none()) {
              const auto a = numericArray(landmarks, "landmarks", -1, 2);
              py::object lid =
                  landmark_ids.is_none()
                      ? py::object(py::module_::import("numpy").attr("arange")(a.shape(0)))
                      : landmark_ids;
              insertBlock(v, kLandmarkKind, lid, a, 2, "landmarks", false);
            }
            return v;
          },
          py::arg("poses"), py::arg("landmarks") = py::none(), py::arg("pose_ids") = py::none(),
          py::arg("landmark_ids") = py::none(),
          "Values from an N x 3 array of poses (ids 0..N-1 unless given) and an M x 2 array of "
          "landmarks (ids 0..M-1 unless given); the inverse of to_numpy().")
      .def("__repr__", [](const Values& v) {
        return "<hamal.Values with " + std::to_string(v.size()) + " variables>";
      });
}

// Values: a mapping Key -> Pose2 or point, and its numpy arrays.
static void bindValues(py::module_& m) {
  py::class_<Values> values(
      m, "Values",
      "The state of a factor graph: one Pose2 or point (a 2-vector) per Key. A mapping: "
      "len(v), key in v, v[key], iteration over the keys (sorted), items(); picklable; "
      "to_numpy()/from_numpy() convert to and from arrays in one pass.");
  bindValuesMapping(values);
  bindValuesArrays(values);
}

// In this order: a class is registered before a signature names it.
void bindGeometry(py::module_& m) {
  bindKey(m);
  bindPose2(m);
  bindValues(m);
}

}  // namespace hamal::python
