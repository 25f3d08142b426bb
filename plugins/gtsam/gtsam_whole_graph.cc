// GtsamWholeGraph: see gtsam_whole_graph.h.
#include "gtsam_whole_graph.h"

#include <utility>

#include "gtsam_factor_adapter.h"

namespace hamal::gtsam_plugin {

std::size_t GtsamWholeGraph::add(const Step& step, const std::string& backend) {
  checkStep(step, estimate, backend);
  gtsam::NonlinearFactorGraph factors = toGtsamFactors(step.new_factors, backend);
  const std::vector<Key> newly_fixed = addFixedPriors(step, estimate, fixed_set, &factors);

  const std::size_t first = graph.size();
  for (const auto& [key, entry] : step.new_values) {
    estimate.insertEntry(key, entry);
    insertGtsamValue(key, entry, &values);
    columns_total += dimension(entry.type);
  }
  graph.push_back(factors.begin(), factors.end());
  for (Key k : newly_fixed) {
    fixed.push_back(k);
    fixed_set.insert(k);
  }
  return first;
}

void GtsamWholeGraph::accept(gtsam::Values solved) {
  values = std::move(solved);
  copyFromGtsam(values, fixed, &estimate);
}

}  // namespace hamal::gtsam_plugin
