// Checked numpy arguments: see numpy_arguments.h.
#include "numpy_arguments.h"

#include <cmath>
#include <sstream>

#include "core/error.h"
#include "core/information.h"

namespace py = pybind11;

namespace hamal::python {

namespace {

std::string shapeText(const py::array& a) {
  std::ostringstream os;
  os << "(";
  for (py::ssize_t i = 0; i < a.ndim(); ++i) os << (i ? ", " : "") << a.shape(i);
  os << (a.ndim() == 1 ? ",)" : ")");
  return os.str();
}

std::string wantedText(long rows, long cols) {
  auto dim = [](long d) { return d < 0 ? std::string("N") : std::to_string(d); };
  return cols == 0 ? "(" + dim(rows) + ",)" : "(" + dim(rows) + ", " + dim(cols) + ")";
}

}  // namespace

py::array_t<double, py::array::c_style> numericArray(py::handle obj, const std::string& name,
                                                     long rows, long cols) {
  py::array raw;
  try {
    raw = py::array::ensure(obj);
  } catch (const py::error_already_set&) {
  }
  if (!raw)
    throw Error(name + ": expected an array of numbers, got " +
                std::string(py::str(py::type::of(obj).attr("__name__"))));
  const char kind = raw.dtype().kind();
  if (kind != 'f' && kind != 'i' && kind != 'u')
    throw Error(name + ": expected real numbers (a float or integer dtype), got dtype " +
                std::string(py::str(raw.dtype())));
  const long ndim = cols == 0 ? 1 : 2;
  const bool shape_ok = raw.ndim() == ndim && (rows < 0 || raw.shape(0) == rows) &&
                        (ndim == 1 || cols < 0 || raw.shape(1) == cols);
  if (!shape_ok)
    throw Error(name + ": expected shape " + wantedText(rows, cols) + ", got " + shapeText(raw));
  auto a = py::array_t<double, py::array::c_style | py::array::forcecast>::ensure(raw);
  if (!a) throw Error(name + ": cannot be read as float64");
  const double* p = a.data();
  for (py::ssize_t i = 0; i < a.size(); ++i)
    if (!std::isfinite(p[i])) {
      std::ostringstream os;
      os << name << ": entry " << i << " is " << p[i] << ", not a finite number";
      throw Error(os.str());
    }
  return a;
}

Eigen::MatrixXd informationMatrix(py::handle obj, const std::string& name, long n) {
  const auto a = numericArray(obj, name, n, n);
  Eigen::MatrixXd m(n, n);
  for (long r = 0; r < n; ++r)
    for (long c = 0; c < n; ++c) m(r, c) = a.at(r, c);
  if (!isSymmetricPositiveDefinite(m)) {
    std::ostringstream os;
    os << name << ": the information matrix is not symmetric positive definite: ["
       << m.format(Eigen::IOFormat(6, 0, ", ", "; ")) << "]";
    throw Error(os.str());
  }
  return m;
}

}  // namespace hamal::python
