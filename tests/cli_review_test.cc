// `doasido review` as a user runs it: help, refusals, study commands.
#include <gtest/gtest.h>

#include "core/config.h"
#include "tests/test_util.h"

namespace doasido {
namespace {

using testing::RunDoasido;
using testing::TempDir;
using testing::WriteFile;

TEST(ReviewCommand, HelpHasExamples) {
  for (const std::vector<std::string>& args :
       {std::vector<std::string>{"review", "--help"}, {"review", "serve", "--help"},
        {"review", "study", "create", "--help"}, {"review", "study", "summary", "--help"}}) {
    const auto r = RunDoasido(args);
    EXPECT_EQ(r.exit_code, 0) << args[1];
    EXPECT_NE(r.out.find("Example"), std::string::npos) << r.out;
  }
}

TEST(ReviewCommand, NonLoopbackHostIsRefusedWithoutAllowRemote) {
  TempDir dir;
  for (const std::string host : {"0.0.0.0", "::", "10.1.2.3"}) {
    const auto r = RunDoasido({"review", "serve", "--db", (dir / "d.db").string(), "--host",
                               host, "--port", "0"});
    EXPECT_EQ(r.exit_code, 1) << host;
    EXPECT_NE(r.err.find("not a loopback address"), std::string::npos) << r.err;
    EXPECT_NE(r.err.find("--allow-remote"), std::string::npos) << r.err;
  }
}

TEST(ReviewCommand, StudyCreateAndEmptySummary) {
  TempDir dir;
  for (const char* f : {"s.mp4", "a.mp4", "b.mp4"}) WriteFile(dir / "m" / f, "x");
  WriteFile(dir / "m" / "items.csv",
            "item_id,a_label,b_label,source_video,a_video,b_video\n"
            "one,ours,base,s.mp4,a.mp4,b.mp4\n"
            "two,ours,base,\"s.mp4\",a.mp4,b.mp4\n");
  WriteFile(dir / "m" / "bad.csv", "item_id,source_video,a_video,b_video,a_label\n");
  const std::string db = (dir / "d.db").string();
  ASSERT_EQ(RunDoasido({"init", "--db", db}).exit_code, 0);  // review only opens a database
  const auto bad = RunDoasido({"review", "study", "create", "--db", db, "--name", "x", "--items",
                               (dir / "m" / "bad.csv").string()});
  EXPECT_EQ(bad.exit_code, 1);
  EXPECT_NE(bad.err.find("b_label"), std::string::npos) << bad.err;
  EXPECT_NE(bad.err.find("bad.csv"), std::string::npos) << bad.err;
  const auto ok = RunDoasido({"review", "study", "create", "--db", db, "--name", "t", "--items",
                              (dir / "m" / "items.csv").string()});
  ASSERT_EQ(ok.exit_code, 0) << ok.err;
  EXPECT_NE(ok.out.find("2 items, 3 raters per item"), std::string::npos) << ok.out;
  const auto summary = RunDoasido({"review", "study", "summary", "--db", db, "--name", "t",
                                   "--json"});
  ASSERT_EQ(summary.exit_code, 0) << summary.err;
  const Json s = Json::parse(summary.out);
  EXPECT_EQ(s.at("items"), 2);
  EXPECT_EQ(s.at("ratings"), 0);
  EXPECT_TRUE(s.at("win_rate_a").is_null());
  EXPECT_TRUE(s.at("fleiss_kappa").is_null());
  const auto missing = RunDoasido({"review", "study", "summary", "--db", db, "--name", "nope"});
  EXPECT_EQ(missing.exit_code, 1);
  EXPECT_NE(missing.err.find("no study named 'nope'"), std::string::npos) << missing.err;
}

}  // namespace
}  // namespace doasido
