// Graph: a factor graph as read from a file or built in code (thesis
// sec. 2.2): the factors, and whatever initial values the source gave
// (g2o and TORO files may list vertices; manhattan.g2o, CSAIL.g2o and the
// GTSAM files list none, and the thesis protocol composes odometry instead).
#pragma once

#include <set>
#include <string>
#include <vector>

#include "core/factor.h"
#include "core/values.h"

namespace hamal {

struct Graph {
  std::string source;              // file name, for messages
  Values initial;                  // may be empty or partial
  std::vector<FactorPtr> factors;  // in file order
  std::set<Key> fixed;             // g2o FIX lines

  void add(FactorPtr factor) { factors.push_back(std::move(factor)); }
  // Every variable the graph names, from its factors and its initial values.
  std::vector<Key> keys() const;
};

}  // namespace hamal
