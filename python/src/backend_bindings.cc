// Back-ends in Python (core/backend.h, core/registry.h, core/plugin.h):
// made by spec string from the module's Registry, fed Steps, returning the
// UpdateResult as an object. Every method holds the handle's lock
// (backend_handle.h), so threads take turns and a call from inside the
// back-end's own update is a RuntimeError. update() copies the step (another
// thread may change it), releases the GIL (a Python factor's cost function
// takes it back, so Ceres' threads may call it) and checks the step's Python
// factors first, so a broken callable is an exception and the back-end stays
// as it was, as checkStep guarantees for bad input.
#include <pybind11/eigen.h>
#include <pybind11/eval.h>
#include <pybind11/stl.h>

#include <chrono>
#include <stdexcept>
#include <unordered_map>

#include "apps/robust/robust_loop_closures.h"
#include "backend_handle.h"
#include "bindings.h"
#include "core/closing_verdict.h"
#include "core/error.h"
#include "core/marginals.h"
#include "core/plugin.h"
#include "core/step.h"
#include "python_factor.h"

namespace py = pybind11;

namespace hamal::python {

namespace {

// The joint marginal covariance of `keys` (core/marginals.h) under the
// handle's lock, the GIL released: cholesky and ceres evaluate the factors
// again, Python factors among them. A back-end without the capability is a
// TypeError, a covariance it cannot give (a failed last update) a
// RuntimeError with its Status' message, bad keys hamal.Error.
Eigen::MatrixXd jointMarginalCovariance(BackendHandle& b, const std::vector<Key>& keys,
                                        const char* what) {
  BackendHandle::Access access(b, what, true);
  auto* marginals = dynamic_cast<MarginalCovariances*>(b.backend.get());
  if (!marginals)
    throw py::type_error(std::string("hamal.Backend.") + what + ": back-end " + b.spec +
                         " does not offer marginal covariances (cholesky, aprilsam, "
                         "aprilsam-top and ceres do)");
  Eigen::MatrixXd out;
  Status status;
  {
    py::gil_scoped_release release;
    status = marginals->jointMarginalCovariance(keys, &out);
  }
  if (!status.ok()) throw std::runtime_error(status.message);
  return out;
}

// Each new Python factor, at the step's new values and the back-end's estimate.
void checkPythonFactors(const Step& step, const Values& known) {
  for (const FactorPtr& f : step.new_factors)
    if (const auto* p = dynamic_cast<const PythonFactor*>(f.get()))
      p->check(step.new_values, known);
}

// The factors given to back-ends, by address; an entry whose factor is gone
// is expired (its address may be reused) and pruned as the map grows.
std::mutex g_held_mutex;
std::unordered_map<const Factor*, std::weak_ptr<const Factor>> g_held;
std::size_t g_held_pruned_at = 1024;

bool heldLocked(const Factor* f) {
  const auto it = g_held.find(f);
  return it != g_held.end() && it->second.lock().get() == f;
}

// Marks the step's factors held; those it newly marked, to unmark when the
// back-end refuses the step.
std::vector<const Factor*> markHeld(const Step& step) {
  std::lock_guard<std::mutex> lock(g_held_mutex);
  if (g_held.size() >= g_held_pruned_at) {
    for (auto it = g_held.begin(); it != g_held.end();)
      it = it->second.expired() ? g_held.erase(it) : std::next(it);
    g_held_pruned_at = std::max<std::size_t>(1024, 2 * g_held.size());
  }
  std::vector<const Factor*> marked;
  for (const FactorPtr& f : step.new_factors)
    if (f && !heldLocked(f.get())) {
      g_held[f.get()] = f;
      marked.push_back(f.get());
    }
  return marked;
}

void unmarkHeld(const std::vector<const Factor*>& marked) {
  std::lock_guard<std::mutex> lock(g_held_mutex);
  for (const Factor* f : marked) g_held.erase(f);
}

}  // namespace

bool heldByBackend(const Factor& factor) {
  std::lock_guard<std::mutex> lock(g_held_mutex);
  return heldLocked(&factor);
}

BackendHandle::Access::Access(BackendHandle& handle, const char* what, bool calls_python)
    : handle_(handle), calls_python_(calls_python) {
  // Waiting here would wait for the caller itself: the lock is held by this
  // thread, or by the update whose Python callback this is (on a thread of
  // the back-end's own, as Ceres' workers).
  if (handle.owner_.load() == std::this_thread::get_id() ||
      (handle.calling_python_.load() && insidePythonCallback()))
    throw std::runtime_error(
        std::string("hamal.Backend.") + what +
        ": called from inside a Python callback (a PythonFactor's function or predict) while " +
        handle.spec +
        "'s update() or steps() runs; the back-end cannot be used before that "
        "call returns");
  lock_ = std::unique_lock<std::mutex>(handle.mutex_, std::try_to_lock);
  if (!lock_.owns_lock()) {
    py::gil_scoped_release release;  // the holder may need the GIL to finish
    lock_.lock();
  }
  handle.owner_ = std::this_thread::get_id();
  if (calls_python_) handle.calling_python_ = true;
}

BackendHandle::Access::~Access() {
  if (calls_python_) handle_.calling_python_ = false;
  handle_.owner_ = std::thread::id();
}

Status BackendHandle::closingVerdict() {
  Access access(*this, "closing_verdict", true);
  auto* verdict = dynamic_cast<ClosingVerdict*>(backend.get());
  if (!verdict) return Status{};
  py::gil_scoped_release release;
  return verdict->closingVerdict();
}

TimedUpdateResult BackendHandle::update(const Step& step_argument) {
  Access access(*this, "update", true);
  const Step step = step_argument;  // the Python object may change once the GIL is released
  checkPythonFactors(step, backend->estimate());
  const std::uint64_t failures_before = pythonFactorFailures();
  const std::vector<const Factor*> marked = markHeld(step);
  TimedUpdateResult out;
  try {
    py::gil_scoped_release release;
    const auto start = std::chrono::steady_clock::now();
    static_cast<UpdateResult&>(out) = backend->update(step);
    out.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  } catch (...) {
    unmarkHeld(marked);  // refused: the back-end holds none of them
    throw;
  }
  if (!out.status.ok() && pythonFactorFailures() != failures_before)
    out.status.message += " (a Python factor failed: " + lastPythonFactorError() + ")";
  return out;
}

// Status, and the codes and update kinds it and UpdateResult name.
static void bindStatus(py::module_& m) {
  // Status.ok's value: an int of 0 or 1 (so it adds, compares and hashes as
  // a bool does; Python's bool cannot be subclassed) that may still be called
  // as the method it was, status.ok(), with a DeprecationWarning.
  py::exec(R"py(
class _CallableBool(int):
    """True or False (an int 0 or 1) that may be called, with a DeprecationWarning,
    as the method it replaces: status.ok() is now status.ok."""

    def __call__(self):
        import warnings
        warnings.warn("Status.ok() is deprecated: Status.ok is a property (status.ok)",
                      DeprecationWarning, stacklevel=2)
        return bool(self)

    def __repr__(self):
        return repr(bool(self))

    __str__ = __repr__
)py",
           m.attr("__dict__"));
  const py::handle callable_bool = m.attr("_CallableBool");  // the module holds it

  py::class_<Status>(m, "Status",
                     "How an update ended: code 'ok'; or 'numerical_failure' naming the "
                     "variables involved, 'not_converged' (an iteration budget spent, or a cost "
                     "above the start), 'uncertain' (a robust answer in doubt; the message names "
                     "the rule). bool(status) is status.ok.")
      .def_property_readonly(
          "code", [](const Status& s) { return std::string(toString(s.code)); },
          "str: one of hamal.STATUS_CODES, 'ok' (converged, nothing casts doubt on it), "
          "'numerical_failure' (a system not positive definite, a solver that cannot proceed; "
          "keys names the variables), 'not_converged' (an iteration budget spent, or a cost "
          "above the start) or 'uncertain' (a robust back-end's answer in doubt; message names "
          "the rule).")
      .def_readonly("message", &Status::message, "Why, for a code other than 'ok' ('' for ok).")
      .def_readonly("keys", &Status::keys,
                    "The variables a numerical failure involves (a new list; may be empty).")
      .def_property_readonly(
          "ok", [callable_bool](const Status& s) { return callable_bool(s.ok() ? 1 : 0); },
          "True when code is 'ok'. (Calling it, status.ok(), still works but is deprecated.)")
      .def("__bool__", &Status::ok)
      .def("__repr__", [](const Status& s) {
        return "<hamal.Status " + std::string(toString(s.code)) +
               (s.message.empty() ? "" : ": " + s.message) + ">";
      });

  py::tuple codes(4);
  for (int c = Status::kOk; c <= Status::kUncertain; ++c)
    codes[c] = std::string(toString(static_cast<Status::Code>(c)));
  m.attr("STATUS_CODES") = codes;
  py::tuple kinds(3);
  for (int k = 0; k < 3; ++k) kinds[k] = std::string(toString(static_cast<UpdateKind>(k)));
  m.attr("UPDATE_KINDS") = kinds;
}

// PhaseTimes: seconds per phase of an update.
static void bindPhaseTimes(py::module_& m) {
  py::class_<PhaseTimes>(m, "PhaseTimes",
                         "Seconds per phase of one update (core/backend.h); a phase a back-end "
                         "does not have is 0.")
      .def_readonly("linearize", &PhaseTimes::linearize,
                    "Seconds evaluating residuals and Jacobians.")
      .def_readonly("order", &PhaseTimes::order, "Seconds choosing the variable ordering.")
      .def_readonly("factor", &PhaseTimes::factor,
                    "Seconds factorising (Cholesky, QR, or the incremental update of R).")
      .def_readonly("solve", &PhaseTimes::solve, "Seconds in back-substitution.")
      .def_readonly("other", &PhaseTimes::other, "Seconds in everything else the back-end timed.")
      .def_readonly("estimate", &PhaseTimes::estimate,
                    "Seconds making the estimate where the back-end computes it apart.")
      .def("total", &PhaseTimes::total, "The sum of the phases (s).")
      .def("__repr__", [](const PhaseTimes& t) {
        return "<hamal.PhaseTimes total " + std::to_string(t.total()) + " s>";
      });
}

// UpdateResult: what one update did.
static void bindUpdateResult(py::module_& m) {
  py::class_<TimedUpdateResult>(m, "UpdateResult", "What one update did (core/backend.h).")
      .def_property_readonly(
          "kind", [](const TimedUpdateResult& r) { return std::string(toString(r.kind)); },
          "str: one of hamal.UPDATE_KINDS, 'none' (nothing solved), 'incremental' (part of the "
          "system updated) or 'batch' (everything relinearised and refactorised).")
      .def_readonly("reason", &UpdateResult::reason,
                    "Why a batch or none, in the back-end's words ('' when incremental).")
      .def_readonly("status", &UpdateResult::status, "Status: how it ended.")
      .def_readonly("iterations", &UpdateResult::iterations,
                    "Nonlinear iterations (Gauss-Newton, LM) this update ran.")
      .def_readonly("variables", &UpdateResult::variables, "Variables after the update.")
      .def_readonly("variables_relinearized", &UpdateResult::variables_relinearized,
                    "Variables whose linearisation point moved in this update.")
      .def_readonly("columns_recomputed", &UpdateResult::columns_recomputed,
                    "Columns of the factor R recomputed (the incremental work).")
      .def_readonly("columns_total", &UpdateResult::columns_total, "Columns of R in all.")
      .def_readonly("time", &UpdateResult::time, "Seconds per phase (hamal.PhaseTimes).")
      .def_readonly("seconds", &TimedUpdateResult::seconds,
                    "Wall time of the update call (steady clock).")
      .def("__repr__", [](const TimedUpdateResult& r) {
        return "<hamal.UpdateResult " + std::string(toString(r.kind)) +
               (r.reason.empty() ? "" : " (" + r.reason + ")") + ", " + toString(r.status.code) +
               ", " + std::to_string(r.seconds) + " s>";
      });
}

// Step: one update's input.
static void bindStep(py::module_& m) {
  py::class_<Step>(m, "Step",
                   "One update's input: new variables with guesses, new factors, fixed keys.")
      .def(py::init([](std::size_t index, const Values& new_values,
                       std::vector<FactorPtr> new_factors, std::vector<Key> fixed) {
             for (std::size_t i = 0; i < new_factors.size(); ++i)
               if (!new_factors[i])
                 throw Error("new_factors: entry " + std::to_string(i) + " is None");
             return Step{index, new_values, std::move(new_factors), std::move(fixed)};
           }),
           py::arg("index") = 0, py::arg("new_values") = Values(),
           py::arg("new_factors") = std::vector<FactorPtr>{}, py::arg("fixed") = std::vector<Key>{},
           "Step(index=0, new_values=Values(), new_factors=[], fixed=[]).")
      .def_readwrite("index", &Step::index, "The step's number (the protocol's pose index).")
      .def_readwrite("new_values", &Step::new_values,
                     "Guesses for the variables this step adds (reading gives a copy).")
      .def_readwrite("new_factors", &Step::new_factors,
                     "The factors this step adds (reading gives a new list).")
      .def_readwrite("fixed", &Step::fixed, "Keys held at their guesses (a new list).")
      .def("__repr__", [](const Step& s) {
        return "<hamal.Step " + std::to_string(s.index) + ": " +
               std::to_string(s.new_values.size()) + " new variables, " +
               std::to_string(s.new_factors.size()) + " factors>";
      });
}

// The robust models that change the loop closures' factors (a loss, a
// max-mixture) are applied by the tools to the graph before it is stepped
// (apps/robust/robust_loop_closures.h, applyRobustMethod); a back-end made
// here only sees the factors the caller steps, so those models would be
// options parsed and never used. GNC and PCM decide inside the back-end and
// are offered.
static void refuseFactorChangingRobustModels(const Options& options) {
  if (!options.values().count("robust")) return;
  const apps::RobustMethod method = apps::robustOptionsFrom(options).method;
  if (!apps::changesFactors(method)) return;
  throw Error(options.owner() + ": robust=" + apps::robustMethodName(method) +
              " changes the loop closures' factors, which a back-end made here cannot: give "
              "the closures a loss with Factor.set_loss (cauchy, huber), or run hamal_robust / "
              "hamal_solve; robust=gnc, gnc-tls, gnc-gm, pcm and pcm+gnc decide in the back-end");
}

// Backend, and hamal.backend(spec) that makes one.
static void bindBackend(py::module_& m) {
  py::class_<BackendHandle>(m, "Backend",
                            "A back-end made by hamal.backend(spec). Threads may share it: each "
                            "call waits for the one in progress (python/README.md).")
      .def("update", &BackendHandle::update, py::arg("step"),
           "Adds the step and updates the estimate; hamal.Error on bad input (the back-end "
           "unchanged). Waits for another thread's call; RuntimeError from inside this "
           "back-end's own callbacks.")
      .def("closing_verdict", &BackendHandle::closingVerdict,
           "The back-end's verdict on its answer once the run is over (hamal.run() asks "
           "for it after the last update): ok, or a Status naming the doubt, e.g. a robust "
           "model's cheaper alternative found over every closure (which gnc_closing=adopt "
           "adopts, so read the estimate after it). ok for a back-end without such checks.")
      .def(
          "estimate",
          [](BackendHandle& b) {
            BackendHandle::Access access(b, "estimate");
            return Values(b.backend->estimate());
          },
          "A copy of the current estimate (O(variables): in a loop, read single variables with "
          "pose()).")
      .def(
          "pose",
          [](BackendHandle& b, Key k) {
            BackendHandle::Access access(b, "pose");
            return b.backend->estimate().pose(k);
          },
          py::arg("key"), "The current estimate of one pose, without copying the estimate.")
      .def(
          "point",
          [](BackendHandle& b, Key k) {
            BackendHandle::Access access(b, "point");
            return b.backend->estimate().point(k);
          },
          py::arg("key"), "The current estimate of one point (an array [x, y], m).")
      .def(
          "marginal_covariance",
          [](BackendHandle& b, Key k) {
            return jointMarginalCovariance(b, {k}, "marginal_covariance");
          },
          py::arg("key"),
          "The covariance of one variable (3x3 for a pose: x, y, theta with x, y in the world "
          "frame; 2x2 for a point) at the back-end's point of linearisation; zero for a fixed "
          "variable. RuntimeError when the last update failed (python/README.md).")
      .def(
          "joint_marginal_covariance",
          [](BackendHandle& b, const std::vector<Key>& keys) {
            return jointMarginalCovariance(b, keys, "joint_marginal_covariance");
          },
          py::arg("keys"),
          "The joint covariance of `keys`, their blocks in that order (see "
          "marginal_covariance).")
      .def("__contains__",
           [](BackendHandle& b, Key k) {
             BackendHandle::Access access(b, "__contains__");
             return b.backend->estimate().contains(k);
           })
      .def("__len__",
           [](BackendHandle& b) {
             BackendHandle::Access access(b, "__len__");
             return b.backend->estimate().size();
           })
      .def_readonly("spec", &BackendHandle::spec, "The spec it was made from.")
      .def_readonly("options", &BackendHandle::options,
                    "Every option with its value, defaults filled in (a dict name -> text).")
      .def("__repr__", [](const BackendHandle& b) { return "<hamal.Backend " + b.spec + ">"; });

  m.def(
      "backend",
      [](const std::string& spec) {
        const BackendSpec parsed = BackendSpec::parse(spec);
        auto h = std::make_unique<BackendHandle>();
        const Options resolved = registry().resolveOptions(parsed);
        refuseFactorChangingRobustModels(resolved);
        h->options = resolved.values();
        h->backend = registry().makeBackend(parsed);
        h->spec = spec;
        return h;
      },
      py::arg("spec"), "A back-end from a spec 'name:key=value,...' (hamal.list_backends()).");
}

// The registry in Python: listings of back-ends and factor kinds, plugins.
static void bindRegistryListings(py::module_& m) {
  m.def(
      "list_backends",
      []() {
        py::list out;
        for (const BackendInfo* b : registry().backends()) {
          py::list options;
          for (const OptionSpec& o : b->options)
            options.append(py::dict(py::arg("name") = o.name, py::arg("default") = o.default_value,
                                    py::arg("help") = o.help));
          out.append(py::dict(py::arg("name") = b->name, py::arg("description") = b->description,
                              py::arg("options") = options));
        }
        return out;
      },
      "Every back-end: name, description and options (name, default, help).");
  m.def(
      "list_factors",
      []() {
        py::list out;
        for (const FactorInfo* f : registry().factors())
          out.append(py::dict(py::arg("format") = f->format, py::arg("tag") = f->tag,
                              py::arg("description") = f->description));
        return out;
      },
      "Every factor kind the readers know: format, tag, description of the fields.");
  m.def(
      "describe_backends", []() { return registry().describeBackends(); },
      "list_backends() as readable text (what hamal_bench --help prints).");
  m.def(
      "describe_factors", []() { return registry().describeFactors(); },
      "list_factors() as readable text.");
  m.def(
      "load_plugin", [](const std::string& path) { loadPlugin(path, registry()); }, py::arg("path"),
      "Loads a plugin's shared library into the module's registry (core/plugin.h).");
  m.def(
      "load_plugins_from_path",
      [](const std::string& env_var) { return loadPluginsFromPath(registry(), env_var.c_str()); },
      py::arg("env_var") = "HAMAL_PLUGIN_PATH",
      "Loads every lib*.so in the directories of the environment variable (':'-separated; done at "
      "import for HAMAL_PLUGIN_PATH) in sorted order; returns their paths.");
}

// In this order: a class is registered before a signature names it.
void bindBackends(py::module_& m) {
  bindStatus(m);
  bindPhaseTimes(m);
  bindUpdateResult(m);
  bindStep(m);
  bindBackend(m);
  bindRegistryListings(m);
}

}  // namespace hamal::python
