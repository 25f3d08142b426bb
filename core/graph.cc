// Graph: see graph.h.
#include "core/graph.h"

namespace hamal {

std::vector<Key> Graph::keys() const {
  std::set<Key> all;
  for (const auto& f : factors) all.insert(f->keys().begin(), f->keys().end());
  for (const auto& kv : initial) all.insert(kv.first);
  return {all.begin(), all.end()};
}

}  // namespace hamal
