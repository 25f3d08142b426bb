// MaximumClique through igraph: see maximum_clique.h.
#include "backends/robust/maximum_clique.h"

#include <igraph.h>
#include <poll.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cstdint>
#include <cstring>
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
    igraph_vector_int_t list;
    check(igraph_vector_int_init(&list, static_cast<igraph_integer_t>(2 * g.edges.size())),
          "vector_int_init");
    for (std::size_t k = 0; k < g.edges.size(); ++k) {
      VECTOR(list)[2 * k] = g.edges[k].first;
      VECTOR(list)[2 * k + 1] = g.edges[k].second;
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

void checkEdges(const ConsistencyGraph& g) {
  if (g.vertices < 0) throw Error("maximum clique: negative vertex count");
  for (const auto& [a, b] : g.edges)
    if (a < 0 || b < 0 || a >= g.vertices || b >= g.vertices || a == b)
      throw Error("maximum clique: edge (" + std::to_string(a) + ", " + std::to_string(b) +
                  ") is not between two vertices of " + std::to_string(g.vertices));
}

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

double since(Clock::time_point t0) {
  return std::chrono::duration<double>(Clock::now() - t0).count();
}

}  // namespace

std::vector<std::vector<int>> largestCliques(const ConsistencyGraph& graph) {
  std::vector<std::vector<int>> out;
  checkEdges(graph);
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

namespace {

CliqueResult cliquerClique(const ConsistencyGraph& graph, const std::vector<bool>& preferred,
                           int ties) {
  Handlers handlers;
  Graph g(graph);
  Collector collector;
  collector.preferred = &preferred;
  collector.ties = std::max(1, ties);
  igraph_integer_t size = 0;
  check(igraph_clique_number(g.get(), &size), "clique_number");
  check(igraph_cliques_callback(g.get(), size, size, collectMaximum, &collector),
        "cliques_callback");
  if (collector.best.empty()) throw Error("maximum clique: igraph returned no clique");
  CliqueResult r;
  r.members = std::move(collector.best);
  return r;
}

// Exact, and fast on the almost complete graphs loop closures give: a
// clique of G takes, from each connected component of G's complement, a
// clique of G restricted to that component, and any such choice is a
// clique (vertices of different components are all joined in G). So the
// maximum clique is the union of each component's, each found by Cliquer;
// a vertex joined to every other is a component of its own.
CliqueResult exactClique(const ConsistencyGraph& graph, const std::vector<bool>& preferred,
                         int ties) {
  const std::size_t n = static_cast<std::size_t>(graph.vertices);
  if (graph.edges.size() * 4 < n * (n - 1)) return cliquerClique(graph, preferred, ties);
  std::vector<std::vector<bool>> joined(n, std::vector<bool>(n, false));
  for (const auto& [a, b] : graph.edges) joined[a][b] = joined[b][a] = true;
  ConsistencyGraph complement{graph.vertices, {}};
  for (std::size_t a = 0; a < n; ++a)
    for (std::size_t b = a + 1; b < n; ++b)
      if (!joined[a][b]) complement.edges.emplace_back(static_cast<int>(a), static_cast<int>(b));
  std::vector<igraph_integer_t> membership(n);
  igraph_integer_t components = 0;
  {
    Handlers handlers;
    Graph g(complement);
    igraph_vector_int_t m;
    check(igraph_vector_int_init(&m, 0), "vector_int_init");
    const igraph_error_t code =
        igraph_connected_components(g.get(), &m, nullptr, &components, IGRAPH_WEAK);
    if (code == IGRAPH_SUCCESS)
      for (std::size_t v = 0; v < n; ++v) membership[v] = VECTOR(m)[v];
    igraph_vector_int_destroy(&m);
    check(code, "connected_components");
  }
  std::vector<std::vector<int>> members(static_cast<std::size_t>(components));
  for (std::size_t v = 0; v < n; ++v) members[membership[v]].push_back(static_cast<int>(v));
  CliqueResult r;
  for (const std::vector<int>& c : members) {
    if (c.size() == 1) {
      r.members.push_back(c[0]);
      continue;
    }
    ConsistencyGraph sub{static_cast<int>(c.size()), {}};
    std::vector<bool> sub_preferred(c.size(), false);
    for (std::size_t a = 0; a < c.size(); ++a) {
      sub_preferred[a] = static_cast<std::size_t>(c[a]) < preferred.size() && preferred[c[a]];
      for (std::size_t b = a + 1; b < c.size(); ++b)
        if (joined[c[a]][c[b]]) sub.edges.emplace_back(static_cast<int>(a), static_cast<int>(b));
    }
    for (int v : cliquerClique(sub, sub_preferred, ties).members) r.members.push_back(c[v]);
  }
  std::sort(r.members.begin(), r.members.end());
  return r;
}

// The exact search in a child process, killed when the budget runs out:
// igraph 0.10.2 cannot be interrupted safely (see g_deadline above), and its
// searches report nothing for minutes on dense graphs of thousands of
// vertices, so a process is the unit that can be stopped.
CliqueResult budgetedClique(const ConsistencyGraph& graph, const std::vector<bool>& preferred,
                            double budget_seconds, int ties, Clock::time_point t0) {
  int fds[2];
  if (pipe(fds) != 0) throw Error("maximum clique: pipe failed");
  const pid_t pid = fork();
  if (pid < 0) {
    close(fds[0]);
    close(fds[1]);
    throw Error("maximum clique: fork failed");
  }
  if (pid == 0) {
    close(fds[0]);
    int code = 0;
    try {
      const CliqueResult r = exactClique(graph, preferred, ties);
      const std::int64_t n = static_cast<std::int64_t>(r.members.size());
      const auto put = [&](const void* data, std::size_t bytes) {
        const char* p = static_cast<const char*>(data);
        while (bytes > 0) {
          const ssize_t w = write(fds[1], p, bytes);
          if (w <= 0) _exit(3);
          p += w;
          bytes -= static_cast<std::size_t>(w);
        }
      };
      put(&n, sizeof n);
      put(r.members.data(), r.members.size() * sizeof(int));
    } catch (...) {
      code = 2;
    }
    close(fds[1]);
    _exit(code);
  }
  close(fds[1]);
  const auto deadline = t0 + std::chrono::duration_cast<Clock::duration>(
                                 std::chrono::duration<double>(budget_seconds));
  std::vector<char> bytes;
  bool timed_out = false;
  for (;;) {
    const auto left =
        std::chrono::duration_cast<std::chrono::milliseconds>(deadline - Clock::now());
    if (left.count() <= 0) {
      timed_out = true;
      break;
    }
    pollfd pfd{fds[0], POLLIN, 0};
    const int ready = poll(&pfd, 1, static_cast<int>(std::min<long long>(left.count(), 1000)));
    if (ready < 0 && errno != EINTR) break;
    if (ready <= 0) continue;
    char buffer[65536];
    const ssize_t got = read(fds[0], buffer, sizeof buffer);
    if (got <= 0) break;  // EOF: the child is done
    bytes.insert(bytes.end(), buffer, buffer + got);
  }
  close(fds[0]);
  if (timed_out) kill(pid, SIGKILL);
  int status = 0;
  while (waitpid(pid, &status, 0) < 0 && errno == EINTR) {
  }
  CliqueResult r;
  if (timed_out) {
    r.exact = false;
    return r;
  }
  std::int64_t n = -1;
  if (!WIFEXITED(status) || WEXITSTATUS(status) != 0 || bytes.size() < sizeof n)
    throw Error("maximum clique: igraph's search failed in its process");
  std::memcpy(&n, bytes.data(), sizeof n);
  if (n < 0 || bytes.size() != sizeof n + static_cast<std::size_t>(n) * sizeof(int))
    throw Error("maximum clique: igraph's search returned a truncated clique");
  r.members.resize(static_cast<std::size_t>(n));
  std::memcpy(r.members.data(), bytes.data() + sizeof n, r.members.size() * sizeof(int));
  return r;
}

}  // namespace

CliqueResult maximumClique(const ConsistencyGraph& graph, const std::vector<bool>& preferred,
                           double budget_seconds, int ties) {
  const auto t0 = Clock::now();
  checkEdges(graph);  // here, not in a child process
  if (graph.vertices == 0) return CliqueResult{};
  CliqueResult r = budget_seconds > 0 ? budgetedClique(graph, preferred, budget_seconds, ties, t0)
                                      : exactClique(graph, preferred, ties);
  r.seconds = since(t0);
  return r;
}

}  // namespace hamal::robust
