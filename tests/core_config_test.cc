#include <gtest/gtest.h>

#include "core/config.h"
#include "core/config_check.h"
#include "tests/test_util.h"

namespace doasido {
namespace {

struct ExampleConfig {
  double threshold = 27.0;
  int min_len = 15;
  std::string mode = "content";
};
NLOHMANN_DEFINE_TYPE_NON_INTRUSIVE_WITH_DEFAULT(ExampleConfig, threshold, min_len, mode)

TEST(Config, TomlSectionOverridesOnlyGivenKeys) {
  testing::TempDir dir;
  testing::WriteFile(dir / "p.toml", "[shots]\nthreshold = 30.5\n\n[other]\nx = 1\n");
  ExampleConfig c;
  ReadSection(LoadConfigFile(dir / "p.toml"), "shots", c);
  EXPECT_DOUBLE_EQ(c.threshold, 30.5);
  EXPECT_EQ(c.min_len, 15);
  EXPECT_EQ(c.mode, "content");
}

TEST(Config, JsonAndTomlGiveTheSameHash) {
  testing::TempDir dir;
  testing::WriteFile(dir / "p.toml", "[shots]\nmin_len = 20\n");
  testing::WriteFile(dir / "p.json", R"({"shots": {"min_len": 20}})");
  ExampleConfig a, b;
  ReadSection(LoadConfigFile(dir / "p.toml"), "shots", a);
  ReadSection(LoadConfigFile(dir / "p.json"), "shots", b);
  EXPECT_EQ(ParamHash(a), ParamHash(b));
  EXPECT_NE(ParamHash(a), ParamHash(ExampleConfig{}));
  EXPECT_EQ(ParamHash(ExampleConfig{}).size(), 16u);
}

TEST(Config, UnknownKeyAndWrongTypeAreNamed) {
  ExampleConfig c;
  try {
    ReadSection(Json{{"shots", {{"treshold", 3}}}}, "shots", c);
    FAIL();
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("shots.treshold"), std::string::npos) << e.what();
  }
  EXPECT_THROW(ReadSection(Json{{"shots", {{"min_len", "many"}}}}, "shots", c), Error);
  // A whole number written as a float passes the shape check, unless int
  // cannot hold it (converting it would be undefined behaviour).
  RequireSameShape("shots", Json(ExampleConfig{}), Json{{"min_len", 20.0}});
  try {
    RequireSameShape("shots", Json(ExampleConfig{}), Json{{"min_len", 3.3e62}});
    FAIL();
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("an integer within"), std::string::npos) << e.what();
  }
}

TEST(Config, TomlSyntaxErrorNamesFileAndLine) {
  testing::TempDir dir;
  testing::WriteFile(dir / "bad.toml", "[shots]\nthreshold = = 3\n");
  try {
    LoadConfigFile(dir / "bad.toml");
    FAIL();
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("bad.toml:2"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace doasido
