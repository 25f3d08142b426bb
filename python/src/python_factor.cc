// PythonFactor: see python_factor.h.
#include "python_factor.h"

#include <pybind11/numpy.h>

#include <atomic>

#include "core/error.h"
#include "core/pose2.h"
#include "numpy_arguments.h"

namespace py = pybind11;

namespace hamal::python {

namespace {

std::atomic<std::uint64_t> g_failures{0};
std::mutex g_error_mutex;
std::string g_last_error;
thread_local int t_callback_depth = 0;

// Marks the thread as running Python code on a back-end's behalf.
struct CallbackScope {
  CallbackScope() { ++t_callback_depth; }
  ~CallbackScope() { --t_callback_depth; }
  CallbackScope(const CallbackScope&) = delete;
  CallbackScope& operator=(const CallbackScope&) = delete;
};

}  // namespace

bool insidePythonCallback() { return t_callback_depth > 0; }

PythonCostFunction::PythonCostFunction(py::function function, int residual_dim,
                                       const std::vector<int>& dims, std::string name)
    : function_(new py::function(std::move(function))), name_(std::move(name)) {
  set_num_residuals(residual_dim);
  *mutable_parameter_block_sizes() = dims;
}

PythonCostFunction::~PythonCostFunction() {
  // A back-end may drop the factor wherever it likes; the reference to the
  // callable is released with the GIL held, or leaked once the interpreter
  // is gone (at exit), never released without it.
  if (Py_IsInitialized()) {
    py::gil_scoped_acquire gil;
    CallbackScope scope;  // the callable's finalizers are Python code too
    delete function_;
  }
}

bool PythonCostFunction::Evaluate(const double* const* parameters, double* residuals,
                                  double** jacobians) const {
  py::gil_scoped_acquire gil;
  CallbackScope scope;
  const auto& dims = parameter_block_sizes();
  const int m = num_residuals();
  std::string error;
  try {
    py::list xs(dims.size());
    for (std::size_t k = 0; k < dims.size(); ++k)
      xs[k] = py::array_t<double>(dims[k], parameters[k]);
    const py::object out = (*function_)(xs);
    if (!py::isinstance<py::tuple>(out) || py::len(out) != 2)
      throw Error("the callable returned " +
                  std::string(py::str(py::type::of(out).attr("__name__"))) +
                  ", expected a tuple (residual, jacobians)");
    const py::tuple t = out.cast<py::tuple>();
    const auto r = numericArray(t[0], "the residual", m, 0);
    for (int i = 0; i < m; ++i) residuals[i] = r.at(i);
    if (jacobians) {
      const py::sequence js = py::reinterpret_borrow<py::sequence>(t[1]);
      if (!py::isinstance<py::sequence>(t[1]) || py::len(js) != dims.size())
        throw Error("the callable returned " +
                    std::to_string(py::isinstance<py::sequence>(t[1]) ? py::len(js) : 0) +
                    " Jacobians, expected " + std::to_string(dims.size()) + " (one per key)");
      for (std::size_t k = 0; k < dims.size(); ++k) {
        if (!jacobians[k]) continue;
        const auto j = numericArray(js[k], "Jacobian " + std::to_string(k), m, dims[k]);
        std::copy(j.data(), j.data() + m * dims[k], jacobians[k]);
      }
    }
    return true;
  } catch (py::error_already_set& e) {
    error = "the callable raised " + std::string(e.what());
  } catch (const std::exception& e) {
    error = e.what();
  }
  const std::string message = name_ + ": " + error;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    last_error_ = message;
    ++failures_;
  }
  {
    std::lock_guard<std::mutex> lock(g_error_mutex);
    g_last_error = message;
  }
  ++g_failures;
  return false;
}

std::string PythonCostFunction::lastError() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return last_error_;
}

std::uint64_t PythonCostFunction::failures() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return failures_;
}

PythonFactor::PythonFactor(std::vector<Key> keys, int residual_dim, py::function function,
                           const std::vector<int>& dims, std::string name, py::object predict)
    : Factor(keys,
             std::make_unique<PythonCostFunction>(std::move(function), residual_dim, dims, name)),
      name_(std::move(name)),
      predict_(predict.is_none() ? nullptr : new py::object(std::move(predict))) {}

PythonFactor::~PythonFactor() {
  if (predict_ && Py_IsInitialized()) {
    py::gil_scoped_acquire gil;
    CallbackScope scope;
    delete predict_;
  }
}

bool PythonFactor::predict(Key unknown, const Values& known, Values::Entry* guess) const {
  if (!predict_) return false;
  // The callable gets its own copy of what it may use, the known variables
  // among the factor's keys: a view of `known` would dangle once the
  // protocol's estimate changes, and a Python callable may keep its argument.
  Values mine;
  for (Key k : keys())
    if (k != unknown && known.contains(k) && !mine.contains(k)) mine.insertEntry(k, known.entry(k));
  py::gil_scoped_acquire gil;
  CallbackScope scope;
  const py::object out = (*predict_)(unknown, std::move(mine));
  if (out.is_none()) return false;
  int dim = 0;
  for (std::size_t k = 0; k < keys().size(); ++k)
    if (keys()[k] == unknown) dim = costFunction()->parameter_block_sizes()[k];
  if (py::isinstance<Pose2>(out)) {
    if (dim != 3)
      throw Error(name_ + ": predict returned a Pose2 for " + unknown.str() + ", of dimension " +
                  std::to_string(dim));
    const Pose2 p = out.cast<Pose2>();
    *guess = {VariableType::kPose2, {p.x, p.y, p.theta}};
    return true;
  }
  if (dim != 2) throw Error(name_ + ": predict must return a Pose2 or None for " + unknown.str());
  const auto a = numericArray(out, name_ + ": predict's result", 2, 0);
  *guess = {VariableType::kPoint2, {a.at(0), a.at(1), 0.0}};
  return true;
}

void PythonFactor::writeFields(std::ostream&) const {
  throw Error(name_ + ": a factor written in Python cannot be written to a file");
}

void PythonFactor::check(const Values& values, const Values& more) const {
  const auto& dims = costFunction()->parameter_block_sizes();
  std::vector<const double*> params;
  for (std::size_t k = 0; k < keys().size(); ++k) {
    const Key key = keys()[k];
    const Values* in = values.contains(key) ? &values : more.contains(key) ? &more : nullptr;
    if (!in || in->dim(key) != dims[k]) return;  // checkStep names the missing or wrong variable
    params.push_back(in->data(key));
  }
  const int m = residualDim();
  std::vector<double> r(m);
  std::vector<std::vector<double>> j(dims.size());
  std::vector<double*> jp(dims.size());
  for (std::size_t k = 0; k < dims.size(); ++k) {
    j[k].resize(std::size_t(m) * dims[k]);
    jp[k] = j[k].data();
  }
  // Evaluate refuses non-finite numbers too (numericArray), naming the entry.
  if (!costFunction()->Evaluate(params.data(), r.data(), jp.data()))
    throw Error(python().lastError());
}

std::uint64_t pythonFactorFailures() { return g_failures.load(); }

std::string lastPythonFactorError() {
  std::lock_guard<std::mutex> lock(g_error_mutex);
  return g_last_error;
}

}  // namespace hamal::python
