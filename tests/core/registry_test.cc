// Registry: names are unique, unknown names list the known ones, variants
// change defaults only, a failed merge adds nothing.
#include "core/registry.h"

#include <gtest/gtest.h>

#include "core/error.h"

namespace hamal {
namespace {

class NullBackend : public Backend {
 public:
  explicit NullBackend(double gain) : gain_(gain) {}
  UpdateResult update(const Step&) override { return {}; }
  const Values& estimate() const override { return values_; }
  double gain_;

 private:
  Values values_;
};

BackendInfo nullInfo(const std::string& name) {
  return {name,
          "does nothing",
          {{"gain", "1.5", "a number"}, {"mode", "a", "a|b"}},
          [](const Options& o) { return std::make_unique<NullBackend>(o.getDouble("gain")); }};
}

TEST(Registry, MakesBackendsBySpec) {
  Registry r;
  r.addBackend(nullInfo("null"));
  auto b = r.makeBackend("null:gain=2");
  EXPECT_EQ(static_cast<NullBackend&>(*b).gain_, 2.0);
  EXPECT_EQ(r.resolveOptions(BackendSpec::parse("null")).str(), "gain=1.5,mode=a");
}

TEST(Registry, UnknownBackendListsRegistered) {
  Registry r;
  r.addBackend(nullInfo("null"));
  r.addBackend(nullInfo("other"));
  try {
    r.makeBackend("nul");
    FAIL();
  } catch (const Error& e) {
    EXPECT_STREQ(e.what(), "unknown back-end 'nul'; registered: null, other");
  }
  EXPECT_THROW(r.makeBackend("null:gian=3"), Error);
}

TEST(Registry, DuplicatesAreErrors) {
  Registry r;
  r.addBackend(nullInfo("null"));
  EXPECT_THROW(r.addBackend(nullInfo("null")), Error);
  EXPECT_THROW(r.addBackend(nullInfo("bad:name")), Error);
  FactorInfo f{"g2o", "EDGE_X", "test", [](LineTokens&) { return FactorPtr(); }};
  r.addFactor(f);
  EXPECT_THROW(r.addFactor(f), Error);
  f.format = "toro";
  EXPECT_NO_THROW(r.addFactor(f));  // same tag, other format
  EXPECT_NE(r.findFactor("toro", "EDGE_X"), nullptr);
  EXPECT_EQ(r.findFactor("gtsam", "EDGE_X"), nullptr);
}

TEST(Registry, VariantChangesDefaultsOnly) {
  Registry r;
  const BackendInfo base = nullInfo("null");
  r.addBackend(base);
  r.addBackend(base.variant("null-b", "mode b", {{"mode", "b"}}));
  EXPECT_EQ(r.resolveOptions(BackendSpec::parse("null-b")).getString("mode"), "b");
  EXPECT_EQ(r.resolveOptions(BackendSpec::parse("null")).getString("mode"), "a");
  EXPECT_THROW(base.variant("x", "", {{"nope", "1"}}), Error);
}

TEST(Registry, FailedMergeAddsNothing) {
  Registry r, staging;
  r.addBackend(nullInfo("null"));
  staging.addBackend(nullInfo("fresh"));
  staging.addBackend(nullInfo("null"));
  EXPECT_THROW(r.merge(staging), Error);
  EXPECT_EQ(r.findBackend("fresh"), nullptr);
  EXPECT_EQ(r.backends().size(), 1u);
}

}  // namespace
}  // namespace hamal
