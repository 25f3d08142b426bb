// Factor: see factor.h.
#include "core/factor.h"

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <limits>
#include <sstream>
#include <typeinfo>

#include "core/error.h"

namespace hamal {

Factor::Factor(std::vector<Key> keys, std::unique_ptr<ceres::CostFunction> cost,
               std::shared_ptr<ceres::LossFunction> loss)
    : keys_(std::move(keys)), cost_(std::move(cost)), loss_(std::move(loss)) {
  if (!cost_) throw Error("Factor: no cost function");
  if (cost_->parameter_block_sizes().size() != keys_.size())
    throw Error("Factor: the cost function has " +
                std::to_string(cost_->parameter_block_sizes().size()) + " parameter blocks for " +
                std::to_string(keys_.size()) + " keys");
}

Factor::~Factor() = default;

bool Factor::evaluate(const Values& values, double* residual) const {
  std::vector<const double*> params;
  params.reserve(keys_.size());
  for (Key k : keys_) params.push_back(values.data(k));
  return cost_->Evaluate(params.data(), residual, nullptr);
}

double Factor::chi2(const Values& values) const {
  std::vector<double> r(residualDim());
  if (!evaluate(values, r.data())) return std::numeric_limits<double>::infinity();
  double s = 0.0;
  for (double v : r) s += v * v;
  return s;
}

namespace {

std::vector<std::string> fieldsOf(const Factor& f) {
  std::ostringstream os;
  f.writeFields(os);
  std::istringstream is(os.str());
  std::vector<std::string> out;
  for (std::string t; is >> t;) out.push_back(t);
  return out;
}

// A field that is a whole number (strtod reads all of it).
bool asNumber(const std::string& s, double* v) {
  char* end = nullptr;
  *v = std::strtod(s.c_str(), &end);
  return !s.empty() && end == s.c_str() + s.size();
}

}  // namespace

bool Factor::nearlyEqual(double a, double b, double tolerance) {
  // NaN compares unequal to everything, as in GTSAM's assert_equal.
  return std::fabs(a - b) <= tolerance * std::max({1.0, std::fabs(a), std::fabs(b)});
}

bool Factor::equals(const Factor& other, double tolerance) const {
  if (this == &other) return true;
  if (typeid(*this) != typeid(other) || keys_ != other.keys_ || tag() != other.tag()) return false;
  const std::vector<std::string> a = fieldsOf(*this), b = fieldsOf(other);
  if (a.size() != b.size()) return false;
  for (std::size_t i = 0; i < a.size(); ++i) {
    double x = 0.0, y = 0.0;
    if (asNumber(a[i], &x) && asNumber(b[i], &y)) {
      if (!nearlyEqual(x, y, tolerance)) return false;
    } else if (a[i] != b[i]) {
      return false;
    }
  }
  return true;
}

}  // namespace hamal
