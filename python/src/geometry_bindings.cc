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
    if (dim == 3) e.data[2] = wrapAngle(e.data[2]);
    overwrite ? values.setEntry(keys[i], e) : values.insertEntry(keys[i], e);
  }
}

}  // namespace

void bindGeometry(py::module_& m) {
  py::class_<Key>(m, "Key",
                  "The name of a variable: a kind letter ('x' pose, 'l' landmark) and an index.")
      .def(py::init(&checkedKey), py::arg("kind"), py::arg("index"))
      .def_property_readonly("kind", [](Key k) { return std::string(1, k.kind()); })
      .def_property_readonly("index", &Key::index)
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

  py::class_<Pose2>(m, "Pose2", "A 2D pose (x, y, theta): the robot's frame in the global frame.")
      .def(py::init([](double x, double y, double theta) { return checkedPose(x, y, theta); }),
           py::arg("x") = 0.0, py::arg("y") = 0.0, py::arg("theta") = 0.0)
      .def(py::init([](py::handle v) {
             const auto a = numericArray(v, "Pose2", 3, 0);
             return Pose2(a.at(0), a.at(1), a.at(2));
           }),
           py::arg("vector"))
      .def_readonly("x", &Pose2::x)
      .def_readonly("y", &Pose2::y)
      .def_readonly("theta", &Pose2::theta)
      .def("compose", &Pose2::compose, py::arg("other"))
      .def("__mul__", &Pose2::compose)
      .def("inverse", &Pose2::inverse)
      .def("between", &Pose2::between, py::arg("other"))
      .def(
          "transform_from",
          [](const Pose2& p, py::handle q) { return p.transformFrom(pointArgument(q, "point")); },
          py::arg("point"))
      .def(
          "transform_to",
          [](const Pose2& p, py::handle q) { return p.transformTo(pointArgument(q, "point")); },
          py::arg("point"))
      .def("translation", &Pose2::t)
      .def("rotation", &Pose2::R)
      .def("vector", [](const Pose2& p) { return Eigen::Vector3d(p.x, p.y, p.theta); })
      .def("matrix",
           [](const Pose2& p) {
             Eigen::Matrix3d t = Eigen::Matrix3d::Identity();
             t.topLeftCorner<2, 2>() = p.R();
             t.topRightCorner<2, 1>() = p.t();
             return t;
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
  m.def("wrap_angle", &wrapAngle, py::arg("angle"), "The angle wrapped to (-pi, pi].");
  m.def(
      "Point2", [](double x, double y) { return Point2(x, y); }, py::arg("x"), py::arg("y"),
      "A 2D point: a numpy array of 2 (as in GTSAM's wrapper).");

  py::class_<Values>(m, "Values", "The state of a factor graph: one Pose2 or point per key.")
      .def(py::init<>())
      .def(py::init([](const Values& v) { return Values(v); }), py::arg("other"))
      .def(
          "insert", [](Values& v, Key k, py::handle value) { put(v, k, value, false); },
          py::arg("key"), py::arg("value"),
          "Adds a variable (a Pose2 or a 2-vector); an Error if the key exists.")
      .def(
          "set", [](Values& v, Key k, py::handle value) { put(v, k, value, true); }, py::arg("key"),
          py::arg("value"), "Inserts or overwrites.")
      .def("erase", &Values::erase, py::arg("key"))
      .def("contains", &Values::contains, py::arg("key"))
      .def("__contains__", &Values::contains)
      .def("__len__", &Values::size)
      .def("size", &Values::size)
      .def("empty", &Values::empty)
      .def("keys", &Values::keys, "Every key, sorted by kind then index.")
      .def("pose", &Values::pose, py::arg("key"))
      .def("atPose2", &Values::pose, py::arg("key"))
      .def("point", &Values::point, py::arg("key"))
      .def("atPoint2", &Values::point, py::arg("key"))
      .def("__getitem__",
           [](const Values& v, Key k) -> py::object {
             if (v.type(k) == VariableType::kPose2) return py::cast(v.pose(k));
             return py::cast(Point2(v.point(k)));
           })
      .def(
          "type", [](const Values& v, Key k) { return std::string(typeName(v.type(k))); },
          py::arg("key"))
      .def("dim", &Values::dim, py::arg("key"))
      .def("copy", [](const Values& v) { return Values(v); })
      .def("__copy__", [](const Values& v) { return Values(v); })
      .def("__deepcopy__", [](const Values& v, py::dict) { return Values(v); })
      .def(
          "poses",
          [](const Values& v) {
            return blockArray(v, keysOf(v, VariableType::kPose2, kPoseKind), 3);
          },
          "The poses x(i) as an N x 3 array (x, y, theta), sorted by i (pose_ids()).")
      .def("pose_ids",
           [](const Values& v) { return indexArray(keysOf(v, VariableType::kPose2, kPoseKind)); })
      .def(
          "landmarks",
          [](const Values& v) {
            return blockArray(v, keysOf(v, VariableType::kPoint2, kLandmarkKind), 2);
          },
          "The landmarks l(j) as an M x 2 array, sorted by j (landmark_ids()).")
      .def("landmark_ids",
           [](const Values& v) {
             return indexArray(keysOf(v, VariableType::kPoint2, kLandmarkKind));
           })
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
          py::arg("ids"), py::arg("poses"))
      .def(
          "set_landmarks",
          [](Values& v, py::handle ids, py::handle points) {
            insertBlock(v, kLandmarkKind, ids, points, 2, "landmarks", true);
          },
          py::arg("ids"), py::arg("landmarks"))
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
          "landmarks.")
      .def("__repr__", [](const Values& v) {
        return "<hamal.Values with " + std::to_string(v.size()) + " variables>";
      });
}

}  // namespace hamal::python
