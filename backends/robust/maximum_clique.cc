// MaximumClique through igraph: see maximum_clique.h.
#include "backends/robust/maximum_clique.h"

#include <igraph.h>

#include <algorithm>
#include <chrono>
#include <string>

#include "core/error.h"

namespace hamal::robust {
namespace {

using Clock = std::chrono::steady_clock;

void check(igraph_error_t code, const char* what) {
  if (code != IGRAPH_SUCCESS)
    throw Error(std::string("maximum clique: igraph failed in ") + what + ": " +
                igraph_strerror(code));
}

// The budget's deadline, read by the enumeration's callback. Not igraph's
// interruption handler: igraph 0.10.2 frees memory it does not own when
// igraph_clique_number is interrupted.
thread_local Clock::time_point g_deadline = Clock::time_point::max();

// igraph's error handler is process-wide; the caller's is put back.
class Handlers {
 public:
  Handlers() : error_(igraph_set_error_handler(igraph_error_handler_ignore)) {}
  ~Handlers() { igraph_set_error_handler(error_); }
  Handlers(const Handlers&) = delete;
  Handlers& operator=(const Handlers&) = delete;

 private:
  igraph_error_handler_t* error_;
};

class Graph {
 public:
  explicit Graph(const ConsistencyGraph& g) {
    if (g.vertices < 0) throw Error("maximum clique: negative vertex count");
    igraph_vector_int_t list;
    check(igraph_vector_int_init(&list, static_cast<igraph_integer_t>(2 * g.edges.size())),
          "vector_int_init");
    for (std::size_t k = 0; k < g.edges.size(); ++k) {
      const auto [a, b] = g.edges[k];
      if (a < 0 || b < 0 || a >= g.vertices || b >= g.vertices || a == b) {
        igraph_vector_int_destroy(&list);
        throw Error("maximum clique: edge (" + std::to_string(a) + ", " + std::to_string(b) +
                    ") is not between two vertices of " + std::to_string(g.vertices));
      }
      VECTOR(list)[2 * k] = a;
      VECTOR(list)[2 * k + 1] = b;
    }
    const igraph_error_t code = igraph_create(&graph_, &list, g.vertices, IGRAPH_UNDIRECTED);
    igraph_vector_int_destroy(&list);
    check(code, "create");
  }
  ~Graph() { igraph_destroy(&graph_); }
  Graph(const Graph&) = delete;
  Graph& operator=(const Graph&) = delete;
  const igraph_t* get() const { return &graph_; }

 private:
  igraph_t graph_;
};

std::vector<int> toSorted(const igraph_vector_int_t* v) {
  std::vector<int> out(static_cast<std::size_t>(igraph_vector_int_size(v)));
  for (std::size_t k = 0; k < out.size(); ++k) out[k] = static_cast<int>(VECTOR(*v)[k]);
  std::sort(out.begin(), out.end());
  return out;
}

int preferredCount(const std::vector<int>& clique, const std::vector<bool>& preferred) {
  int n = 0;
  for (int v : clique)
    if (static_cast<std::size_t>(v) < preferred.size() && preferred[v]) ++n;
  return n;
}

// What the clique callbacks keep: the best clique so far by (size, preferred).
struct Collector {
  const std::vector<bool>* preferred = nullptr;
  std::vector<int> best;
  int best_preferred = -1;
  int seen = 0, ties = 0;
  bool stopped = false;
  void offer(std::vector<int> clique) {
    const int p = preferredCount(clique, *preferred);
    if (clique.size() > best.size() || (clique.size() == best.size() && p > best_preferred)) {
      best = std::move(clique);
      best_preferred = p;
    }
  }
};

igraph_error_t collectMaximum(const igraph_vector_int_t* clique, void* arg) {
  auto* c = static_cast<Collector*>(arg);
  c->offer(toSorted(clique));
  return ++c->seen >= c->ties ? IGRAPH_STOP : IGRAPH_SUCCESS;
}

igraph_error_t collectMaximal(const igraph_vector_int_t* clique, void* arg) {
  auto* c = static_cast<Collector*>(arg);
  c->offer(toSorted(clique));
  c->stopped = Clock::now() > g_deadline;
  return c->stopped ? IGRAPH_STOP : IGRAPH_SUCCESS;
}

double since(Clock::time_point t0) {
  return std::chrono::duration<double>(Clock::now() - t0).count();
}

}  // namespace

std::vector<std::vector<int>> largestCliques(const ConsistencyGraph& graph) {
  std::vector<std::vector<int>> out;
  if (graph.vertices == 0) return out;
  Handlers handlers;
  Graph g(graph);
  igraph_vector_int_list_t cliques;
  check(igraph_vector_int_list_init(&cliques, 0), "vector_int_list_init");
  const igraph_error_t code = igraph_largest_cliques(g.get(), &cliques);
  if (code == IGRAPH_SUCCESS)
    for (igraph_integer_t c = 0; c < igraph_vector_int_list_size(&cliques); ++c)
      out.push_back(toSorted(igraph_vector_int_list_get_ptr(&cliques, c)));
  igraph_vector_int_list_destroy(&cliques);
  check(code, "largest_cliques");
  return out;
}

CliqueResult maximumClique(const ConsistencyGraph& graph, const std::vector<bool>& preferred,
                           double budget_seconds, int ties) {
  CliqueResult result;
  if (graph.vertices == 0) return result;
  const auto t0 = Clock::now();
  Handlers handlers;
  Graph g(graph);
  Collector collector;
  collector.preferred = &preferred;
  collector.ties = std::max(1, ties);
  if (budget_seconds > 0) {
    // Every maximal clique, the largest kept, until the budget runs out: a
    // complete enumeration is exact.
    g_deadline = t0 + std::chrono::duration_cast<Clock::duration>(
                          std::chrono::duration<double>(budget_seconds));
    check(igraph_maximal_cliques_callback(g.get(), collectMaximal, &collector, 0, 0),
          "maximal_cliques_callback");
    result.exact = !collector.stopped;
  } else {
    igraph_integer_t size = 0;
    check(igraph_clique_number(g.get(), &size), "clique_number");
    check(igraph_cliques_callback(g.get(), size, size, collectMaximum, &collector),
          "cliques_callback");
  }
  result.members = std::move(collector.best);
  if (result.members.empty()) throw Error("maximum clique: igraph returned no clique");
  result.seconds = since(t0);
  return result;
}

}  // namespace hamal::robust
