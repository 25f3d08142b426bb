// The plugin mechanism (core/plugin.h, core/plugin_loader.cc) and the example
// plugin (plugins/example): loaded by path at run time, never linked, its
// factor kind read from g2o text and solved with its own back-end and with a
// built-in one; and every way loading can fail gives a clear Error and leaves
// the registry as it was (the staging registry is merged all or nothing).
#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <sstream>

#include "backends/builtins.h"
#include "core/error.h"
#include "core/graph_io.h"
#include "core/metrics.h"
#include "core/plugin.h"
#include "protocol/thesis_protocol.h"
#include "testing/test_data.h"

namespace hamal {
namespace {

std::string pluginPath() { return testing::buildPath("plugins/libhamal_example_plugin.so"); }

// Everything a registry holds, to check that a failed load changed nothing.
std::string contents(const Registry& r) { return r.describeBackends() + r.describeFactors(); }

Registry builtinsWithPlugin() {
  Registry registry;
  registerBuiltins(registry);
  loadPlugin(pluginPath(), registry);
  return registry;
}

// A square driven twice around (8 poses), odometry as plain EDGE_SE2, the
// loop closures as the plugin's EDGE_SE2_CAUCHY; the last closure is an
// outlier (5 m off) that the Cauchy loss should mostly ignore.
const char kCauchyGraph[] =
    "EDGE_SE2 0 1 1.02 0.01 1.5708 100 0 0 100 0 400\n"
    "EDGE_SE2 1 2 0.98 -0.02 1.5608 100 0 0 100 0 400\n"
    "EDGE_SE2 2 3 1.01 0.00 1.5808 100 0 0 100 0 400\n"
    "EDGE_SE2 3 4 0.99 0.03 1.5708 100 0 0 100 0 400\n"
    "EDGE_SE2 4 5 1.00 -0.01 1.5708 100 0 0 100 0 400\n"
    "EDGE_SE2 5 6 1.03 0.02 1.5658 100 0 0 100 0 400\n"
    "EDGE_SE2 6 7 0.97 0.00 1.5758 100 0 0 100 0 400\n"
    "EDGE_SE2_CAUCHY 0 4 0.01 -0.02 0.01 100 0 0 100 0 400 1.0\n"
    "EDGE_SE2_CAUCHY 1 5 -0.02 0.01 -0.01 100 0 0 100 0 400 1.0\n"
    "EDGE_SE2_CAUCHY 3 7 5.0 5.0 0.0 100 0 0 100 0 400 1.0\n";

Graph readCauchyGraph(const Registry& registry) {
  std::istringstream in(kCauchyGraph);
  return readGraph(in, "cauchy.g2o", registry, Format::kG2o);
}

struct Solved {
  Values estimate;
  UpdateResult result;
};

Solved solveBatch(const Registry& registry, const std::string& spec, const Graph& graph) {
  auto backend = registry.makeBackend(spec);
  ThesisProtocol protocol(graph);
  Solved out;
  out.result = backend->update(protocol.batch());
  out.estimate = backend->estimate();
  return out;
}

TEST(ExamplePlugin, RegistersItsFactorKindAndBackEnd) {
  Registry registry;
  registerBuiltins(registry);
  const std::string before = contents(registry);
  ASSERT_EQ(registry.findBackend("dense-gauss-newton"), nullptr);
  loadPlugin(pluginPath(), registry);
  EXPECT_NE(registry.findFactor("g2o", "EDGE_SE2_CAUCHY"), nullptr);
  const BackendInfo* info = registry.findBackend("dense-gauss-newton");
  ASSERT_NE(info, nullptr);
  std::vector<std::string> names;
  for (const auto& o : info->options) names.push_back(o.name);
  EXPECT_EQ(names, (std::vector<std::string>{"max_iterations", "tolerance"}));
  // Built-ins are still there.
  EXPECT_NE(registry.findBackend("cholesky"), nullptr);
  EXPECT_NE(contents(registry), before);
}

TEST(ExamplePlugin, CauchyFactorsAreReadAndSolvedByThePluginAndByCholesky) {
  const Registry registry = builtinsWithPlugin();
  const Graph graph = readCauchyGraph(registry);
  ASSERT_EQ(graph.factors.size(), 10u);
  EXPECT_EQ(graph.factors[7]->tag(), "EDGE_SE2_CAUCHY");
  ASSERT_NE(graph.factors[7]->lossFunction(), nullptr);
  EXPECT_EQ(graph.factors[0]->lossFunction(), nullptr);

  const ThesisProtocol protocol(graph);
  // chi2 has no loss, so the outlier's term may grow; the inliers' must fall.
  const std::vector<FactorPtr> inliers(graph.factors.begin(), graph.factors.end() - 1);
  const double before = chi2(inliers, protocol.initialValues());
  const Solved dense =
      solveBatch(registry, "dense-gauss-newton:max_iterations=50,tolerance=1e-10", graph);
  const Solved cholesky = solveBatch(registry, "cholesky", graph);
  ASSERT_TRUE(dense.result.status.ok()) << dense.result.status.message;
  ASSERT_TRUE(cholesky.result.status.ok()) << cholesky.result.status.message;
  EXPECT_GT(dense.result.iterations, 0);
  EXPECT_EQ(dense.result.kind, UpdateKind::kBatch);
  EXPECT_EQ(dense.estimate.size(), 8u);

  // Both minimise the same robust objective: the same optimum.
  for (Key k : dense.estimate.keys()) {
    const Pose2 a = dense.estimate.pose(k), b = cholesky.estimate.pose(k);
    EXPECT_NEAR(a.x, b.x, 1e-4) << k;
    EXPECT_NEAR(a.y, b.y, 1e-4) << k;
    EXPECT_NEAR(wrapAngle(a.theta - b.theta), 0.0, 1e-4) << k;
  }
  const double dense_chi2 = chi2(graph.factors, dense.estimate);
  EXPECT_NEAR(dense_chi2, chi2(graph.factors, cholesky.estimate), 1e-4 * dense_chi2);
  EXPECT_LT(chi2(inliers, dense.estimate), 0.5 * before);

  // The Cauchy loss keeps the outlier (3 -> 7, 7 m off) from bending the
  // square: pose 7 stays where odometry and the good closures put it, on
  // pose 3, the same corner on the second lap.
  const Pose2 p3 = dense.estimate.pose(X(3)), p7 = dense.estimate.pose(X(7));
  EXPECT_LT(std::hypot(p7.x - p3.x, p7.y - p3.y), 0.5);
}

TEST(ExamplePlugin, CauchyFactorsRoundTripThroughG2o) {
  const Registry registry = builtinsWithPlugin();
  const Graph graph = readCauchyGraph(registry);
  const ThesisProtocol protocol(graph);
  std::ostringstream written;
  writeG2o(written, protocol.initialValues(), graph.factors);
  EXPECT_NE(written.str().find("EDGE_SE2_CAUCHY 3 7 5 5 0 100 0 0 100 0 400 1\n"),
            std::string::npos)
      << written.str();
  std::istringstream in(written.str());
  const Graph again = readGraph(in, "again.g2o", registry, Format::kG2o);
  ASSERT_EQ(again.factors.size(), graph.factors.size());
  EXPECT_EQ(again.factors[9]->tag(), "EDGE_SE2_CAUCHY");
  // Factor::equals compares the plugin's scale too: it is in its file form.
  for (std::size_t i = 0; i < graph.factors.size(); ++i)
    EXPECT_TRUE(again.factors[i]->equals(*graph.factors[i], 0.0)) << i;
  EXPECT_FALSE(again.factors[9]->equals(*again.factors[8]));
  EXPECT_DOUBLE_EQ(chi2(again.factors, again.initial),
                   chi2(graph.factors, protocol.initialValues()));
}

TEST(ExamplePlugin, BadCauchyScaleIsAReadError) {
  const Registry registry = builtinsWithPlugin();
  std::istringstream in("EDGE_SE2_CAUCHY 0 1 1 0 0 100 0 0 100 0 400 -2\n");
  try {
    readGraph(in, "bad.g2o", registry, Format::kG2o);
    FAIL() << "a negative Cauchy scale was accepted";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("bad.g2o:1"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("scale"), std::string::npos) << e.what();
  }
}

// EDGE_MAXMIX reads its inner line through the registry, so it sees the
// plugin's tag; a component with a robust loss is refused, by name.
TEST(ExamplePlugin, AMaxMixtureLineFindsThePluginsTagAndRefusesItsLoss) {
  const Registry registry = builtinsWithPlugin();
  std::istringstream in(
      "EDGE_SE2 0 1 1 0 0 100 0 0 100 0 400\n"
      "EDGE_MAXMIX 0.1 1e-6 EDGE_SE2_CAUCHY 0 1 1 0 0 100 0 0 100 0 400 1.0\n");
  try {
    readGraph(in, "mix.g2o", registry, Format::kG2o);
    FAIL() << "a Cauchy component was accepted";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("mix.g2o:2"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("EDGE_SE2_CAUCHY) has a robust loss"), std::string::npos)
        << e.what();
  }
}

TEST(ExamplePlugin, DenseGaussNewtonReportsASingularSystemAsAStatus) {
  const Registry registry = builtinsWithPlugin();
  Graph graph = readCauchyGraph(registry);
  // Without the protocol's prior the graph floats (gauge freedom).
  ThesisProtocol::Options options;
  options.add_prior = false;
  const ThesisProtocol protocol(graph, options);
  auto backend = registry.makeBackend("dense-gauss-newton");
  UpdateResult result;
  ASSERT_NO_THROW(result = backend->update(protocol.batch()));
  EXPECT_EQ(result.status.code, Status::kNumericalFailure);
  EXPECT_FALSE(result.status.keys.empty());
  EXPECT_NE(result.status.message.find("singular"), std::string::npos) << result.status.message;
}

TEST(ExamplePlugin, DenseGaussNewtonRejectsBadOptions) {
  const Registry registry = builtinsWithPlugin();
  EXPECT_THROW(registry.makeBackend("dense-gauss-newton:max_iterations=0"), Error);
  try {
    registry.makeBackend("dense-gauss-newton:iterations=3");
    FAIL();
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("max_iterations, tolerance"), std::string::npos)
        << e.what();
  }
}

// Every failure: a message naming the file and the reason, nothing registered.
void expectLoadFails(const std::string& path, const std::string& reason) {
  Registry registry;
  registerBuiltins(registry);
  const std::string before = contents(registry);
  try {
    loadPlugin(path, registry);
    FAIL() << "loading " << path << " did not fail";
  } catch (const Error& e) {
    const std::string message = e.what();
    EXPECT_NE(message.find(path), std::string::npos) << message;
    EXPECT_NE(message.find(reason), std::string::npos) << message;
  }
  EXPECT_EQ(contents(registry), before);
}

TEST(PluginLoader, MissingFile) {
  expectLoadFails(testing::buildPath("plugins/libno_such_plugin.so"), "cannot load");
}

TEST(PluginLoader, SharedLibraryThatIsNotAPlugin) {
  // libhamal itself is a shared library without the entry point.
  expectLoadFails(testing::buildPath("libhamal.so"),
                  "no hamal_plugin_register symbol: is this a hamal plugin?");
}

TEST(PluginLoader, FileThatIsNotASharedLibrary) {
  const std::string path = ::testing::TempDir() + "/libhamal_test_not_elf.so";
  std::ofstream(path) << "this is not an ELF file\n";
  expectLoadFails(path, "cannot load");
  std::remove(path.c_str());
}

TEST(PluginLoader, LoadingTheSamePluginTwiceIsADuplicateAndAddsNothing) {
  Registry registry = builtinsWithPlugin();
  const std::string before = contents(registry);
  try {
    loadPlugin(pluginPath(), registry);
    FAIL() << "a second load registered the same names again";
  } catch (const Error& e) {
    const std::string message = e.what();
    EXPECT_NE(message.find(pluginPath()), std::string::npos) << message;
    EXPECT_NE(message.find("already registered"), std::string::npos) << message;
  }
  EXPECT_EQ(contents(registry), before);
}

TEST(PluginLoader, ClashWithABuiltInNameAddsNothing) {
  // A registry that already has a back-end called dense-gauss-newton: the
  // plugin's factor kind must not be added either.
  Registry registry;
  registerBuiltins(registry);
  BackendInfo squatter = *registry.findBackend("cholesky");
  squatter.name = "dense-gauss-newton";
  registry.addBackend(squatter);
  const std::string before = contents(registry);
  EXPECT_THROW(loadPlugin(pluginPath(), registry), Error);
  EXPECT_EQ(registry.findFactor("g2o", "EDGE_SE2_CAUCHY"), nullptr);
  EXPECT_EQ(contents(registry), before);
}

TEST(PluginLoader, LoadsEveryPluginOfTheSearchPath) {
  std::string empty_dir = ::testing::TempDir() + "/hamal_plugin_path_XXXXXX";
  ASSERT_NE(mkdtemp(empty_dir.data()), nullptr);
  const std::string value = empty_dir + "::" + testing::buildPath("plugins");
  ASSERT_EQ(setenv("HAMAL_TEST_PLUGIN_PATH", value.c_str(), 1), 0);
  Registry registry;
  registerBuiltins(registry);
  const auto loaded = loadPluginsFromPath(registry, "HAMAL_TEST_PLUGIN_PATH");
#ifdef HAMAL_GTSAM_PLUGIN  // the GTSAM plugin is built beside it (plugins/gtsam)
  ASSERT_EQ(loaded.size(), 2u);
  EXPECT_EQ(loaded[1], testing::buildPath("plugins") + "/libhamal_gtsam_plugin.so");
#else
  ASSERT_EQ(loaded.size(), 1u);
#endif
  EXPECT_EQ(loaded[0], testing::buildPath("plugins") + "/libhamal_example_plugin.so");
  EXPECT_NE(registry.findBackend("dense-gauss-newton"), nullptr);

  // Unset: nothing to load. A directory that does not exist: an error.
  unsetenv("HAMAL_TEST_PLUGIN_PATH");
  EXPECT_TRUE(loadPluginsFromPath(registry, "HAMAL_TEST_PLUGIN_PATH").empty());
  setenv("HAMAL_TEST_PLUGIN_PATH", "/no/such/dir", 1);
  EXPECT_THROW(loadPluginsFromPath(registry, "HAMAL_TEST_PLUGIN_PATH"), Error);
  unsetenv("HAMAL_TEST_PLUGIN_PATH");
  rmdir(empty_dir.c_str());
}

}  // namespace
}  // namespace hamal
