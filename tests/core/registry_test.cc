// Registry: names are unique, unknown names list the known ones, variants
// change defaults only, a failed merge adds nothing.
#include "core/registry.h"

#include <ceres/numeric_diff_cost_function.h>
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

// A factor kind for the wrapping test: a prior-like factor on one pose.
class TagFactor : public Factor {
 public:
  TagFactor(Key k, std::string tag)
      : Factor({k}, std::make_unique<ceres::NumericDiffCostFunction<Zero, ceres::CENTRAL, 1, 3>>(
                        new Zero)),
        tag_(std::move(tag)) {}
  std::string tag() const override { return tag_; }
  void writeFields(std::ostream&) const override {}
  struct Zero {
    bool operator()(const double*, double* r) const {
      r[0] = 0;
      return true;
    }
  };

 private:
  std::string tag_;
};

// A parse function reads an inner line through the registry it is read
// with, not one it captured: a kind registered in a plugin's staging
// registry wraps kinds of the registry it is merged into.
TEST(Registry, AParseFunctionReadsAnInnerLineThroughTheReadingRegistry) {
  Registry r;
  r.addFactor({"g2o", "EDGE_ONE", "one id", [](LineTokens& t) -> FactorPtr {
                 return std::make_shared<TagFactor>(X(t.id("id")), "EDGE_ONE");
               }});
  Registry staging;
  staging.addFactor({"g2o", "WRAP", "wraps a line", [](LineTokens& t) -> FactorPtr {
                       const double w = t.number("w");
                       FactorPtr inner = t.registry()->parseFactor(t.rest("inner tag"));
                       return std::make_shared<TagFactor>(inner->keys()[0],
                                                          "WRAP" + std::to_string(int(w)));
                     }});
  r.merge(staging);
  LineTokens line = LineTokens::split("w.g2o", 4, "WRAP 7 EDGE_ONE 12");
  line.setRegistry(&r, "g2o");
  const FactorPtr f = r.parseFactor(line);
  EXPECT_EQ(f->tag(), "WRAP7");
  EXPECT_EQ(f->keys(), std::vector<Key>{X(12)});

  auto error = [&](const std::string& text) -> std::string {
    LineTokens l = LineTokens::split("w.g2o", 4, text);
    l.setRegistry(&r, "g2o");
    try {
      r.parseFactor(l);
    } catch (const Error& e) {
      return e.what();
    }
    return "";
  };
  EXPECT_EQ(error("WRAP 7 EDGE_TWO 12"),
            "w.g2o:4: unknown tag 'EDGE_TWO' for format g2o; known factor tags: EDGE_ONE, WRAP");
  EXPECT_EQ(error("WRAP 7"),
            "w.g2o:4: WRAP line is truncated: it has 1 fields, inner tag is missing");
  EXPECT_EQ(error("WRAP 7 EDGE_ONE 12 13"),
            "w.g2o:4: EDGE_ONE line has 2 fields, expected 1 (extra: '13')");
  EXPECT_EQ(error("WRAP 7 EDGE_ONE"),
            "w.g2o:4: EDGE_ONE line is truncated: it has 0 fields, id is missing");
}

}  // namespace
}  // namespace hamal
