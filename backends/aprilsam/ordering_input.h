// OrderingInput: the variable graph that AprilSAM's fill-reducing orderings
// see (thesis sec. 3.4.3): one node per variable, whatever its dimension, so
// an ordering of nodes is an ordering of the 3x3 / 2x2 blocks of the normal
// equations. Positions feed the loop-closure score of eq. 3.20; `newest` is
// the pose the next factor will most likely touch.
#pragma once

#include <Eigen/Core>
#include <algorithm>
#include <string>
#include <vector>

#include "core/error.h"

namespace hamal::aprilsam {

struct OrderingInput {
  // Node ids 0..n-1. Meant to be symmetric without self loops; the orderings
  // use the pattern of A + A^T and ignore self loops and duplicate entries,
  // so a one-sided list is not an error. An id outside 0..n-1 is.
  std::vector<std::vector<int>> adjacency;
  // Each node's position (pose translation or landmark point). Only
  // minHeapOrdering reads it, and only when `newest` >= 0.
  std::vector<Eigen::Vector2d> positions;
  int newest = -1;  // the most recently added pose (-1: none)
};

// The pattern of A + A^T without the diagonal, each list sorted and without
// duplicates: what every ordering works on, in the first n lists of `sym`
// (n = in.adjacency.size(); sym grows to n lists, and longer ones keep
// their lists and buffers, so a caller that orders many graphs reuses
// them). Throws hamal::Error on an id outside 0..n-1 or a `newest` that
// names no node.
inline void symmetricAdjacency(const OrderingInput& in, std::vector<std::vector<int>>* sym) {
  const int n = static_cast<int>(in.adjacency.size());
  if (in.newest < -1 || in.newest >= n) {
    throw Error("ordering: newest node " + std::to_string(in.newest) + " is not in 0.." +
                std::to_string(n - 1));
  }
  // Counted first, so each list is allocated once at its size: a batch
  // orders the whole map, and growing n lists by doubling was most of the
  // ordering's malloc calls.
  std::vector<int> count(n, 0);
  for (int i = 0; i < n; ++i) {
    for (int j : in.adjacency[i]) {
      if (j < 0 || j >= n) {
        throw Error("ordering: node " + std::to_string(i) + " has neighbour " + std::to_string(j) +
                    " outside 0.." + std::to_string(n - 1));
      }
      if (j == i) continue;
      ++count[i];
      ++count[j];
    }
  }
  if (static_cast<int>(sym->size()) < n) sym->resize(n);
  for (int i = 0; i < n; ++i) {
    (*sym)[i].clear();
    (*sym)[i].reserve(count[i]);
  }
  for (int i = 0; i < n; ++i) {
    for (int j : in.adjacency[i]) {
      if (j == i) continue;
      (*sym)[i].push_back(j);
      (*sym)[j].push_back(i);
    }
  }
  for (int i = 0; i < n; ++i) {
    std::vector<int>& list = (*sym)[i];
    std::sort(list.begin(), list.end());
    list.erase(std::unique(list.begin(), list.end()), list.end());
  }
}

inline std::vector<std::vector<int>> symmetricAdjacency(const OrderingInput& in) {
  std::vector<std::vector<int>> sym;
  symmetricAdjacency(in, &sym);
  return sym;
}

}  // namespace hamal::aprilsam
