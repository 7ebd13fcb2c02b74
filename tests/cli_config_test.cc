// A bad --config is refused before any clip is claimed: `doasido run`,
// `worker`, `rethreshold` and `init` exit with code 2 and a message naming
// the file, the section and key, and the queue is left as it was.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "db/database.h"
#include "tests/test_util.h"

namespace doasido {
namespace {

using ::testing::HasSubstr;
using testing::RunDoasido;
using testing::SharedData;
using testing::TempDir;
using testing::WriteFile;

struct BadConfig {
  std::string name;
  std::string file;  // file name (its extension picks TOML or JSON)
  std::string text;
  std::string field;  // section.key the message must name
  std::string detail;  // and this part of the reason
};

// Every run of the queue as (stage, state, attempts, verdict).
std::vector<std::string> QueueState(const std::filesystem::path& db_path) {
  Database db(db_path);
  std::vector<std::string> rows;
  for (const auto& r : db.ListRuns({})) {
    rows.push_back(r.stage + " " + ToString(r.state) + " " + std::to_string(r.attempts) + " " +
                   r.verdict);
  }
  return rows;
}

class CliConfigTest : public ::testing::TestWithParam<BadConfig> {
 protected:
  void SetUp() override {
    const auto v = SharedData() / "videos";
    WriteFile(dir_ / "clips.csv", "video,id,start_frame,end_frame\n" +
                                      (v / "02_cups.mp4").string() + ",cups,0,29\n" +
                                      (v / "apple.mp4").string() + ",apple,,\n");
    ASSERT_EQ(RunDoasido({"init", "--db", db_.string(), "--pipeline", "noop"}).exit_code, 0);
    ASSERT_EQ(RunDoasido({"ingest", "--db", db_.string(), (dir_ / "clips.csv").string()})
                  .exit_code,
              0);
    before_ = QueueState(db_);
    ASSERT_EQ(before_.size(), 2u);
  }

  TempDir dir_;
  std::filesystem::path db_ = dir_ / "d.db";
  std::vector<std::string> before_;
};

// Checks that `command` refuses `bad` (written to a file) with exit code 2
// and a message naming the file, section.key and the reason, and leaves the
// queue as it was.
void ExpectRefused(const std::vector<std::string>& command, const BadConfig& bad,
                   const std::filesystem::path& config, const std::filesystem::path& db,
                   const std::vector<std::string>& before) {
  const auto r = RunDoasido(command);
  EXPECT_EQ(r.exit_code, 2) << command[0] << ": " << r.out << r.err;
  EXPECT_THAT(r.err, HasSubstr(config.string())) << command[0];
  EXPECT_THAT(r.err, HasSubstr("field " + bad.field)) << command[0];
  EXPECT_THAT(r.err, HasSubstr(bad.detail)) << command[0];
  EXPECT_EQ(QueueState(db), before) << command[0] << " changed the queue";
}

TEST_P(CliConfigTest, RunRefusesItBeforeAnyClipIsClaimed) {
  const BadConfig& bad = GetParam();
  const auto config = dir_ / bad.file;
  WriteFile(config, bad.text);
  ExpectRefused({"run", "--db", db_.string(), "--config", config.string()}, bad, config, db_,
                before_);
}

// The other commands that take --config refuse it the same way.
TEST_F(CliConfigTest, WorkerRethresholdAndInitRefuseItToo) {
  const BadConfig bad{"OutOfRange", "strict.toml", "[activity]\nmin_active_fraction = -0.3\n",
                      "activity.min_active_fraction", "value -0.3 is out of range [0, 1]"};
  const auto config = dir_ / bad.file;
  WriteFile(config, bad.text);
  const std::string c = config.string(), d = db_.string();
  ExpectRefused({"worker", "--db", d, "--until-empty", "--config", c}, bad, config, db_, before_);
  ExpectRefused({"rethreshold", "--db", d, "--config", c}, bad, config, db_, before_);
  ExpectRefused({"init", "--db", d, "--config", c}, bad, config, db_, before_);
}

INSTANTIATE_TEST_SUITE_P(
    EachMistake, CliConfigTest,
    ::testing::Values(
        BadConfig{"TypoedKey", "typo.toml", "[activity]\nmin_activ_fraction = 0.3\n",
                  "activity.min_activ_fraction", "unknown key"},
        BadConfig{"NegativeThreshold", "negative.toml", "[shot_boundary]\ncontent_threshold = -5\n",
                  "shot_boundary.content_threshold", "value -5 is out of range [0, 255]"},
        BadConfig{"NaN", "nan.toml", "[camera_motion]\nreject_rotation_rate = nan\n",
                  "camera_motion.reject_rotation_rate", "is out of range [0, 100]"},
        BadConfig{"StringForANumber", "string.json",
                  R"({"interaction": {"min_interaction_fraction": "high"}})",
                  "interaction.min_interaction_fraction", "expects a number, got \"high\""},
        BadConfig{"UnknownSection", "section.toml", "[activityy]\nmin_active_fraction = 0.3\n",
                  "activityy", "unknown section [activityy]"},
        BadConfig{"OutOfRangeFraction", "fraction.toml", "[activity]\nmin_active_fraction = 1.5\n",
                  "activity.min_active_fraction", "value 1.5 is out of range [0, 1]"},
        BadConfig{"NestedOutOfRange", "nested.toml",
                  "[retarget_kinematic.scene.decomposition]\nmin_solidity = 2\n",
                  "retarget_kinematic.scene.decomposition.min_solidity",
                  "value 2 is out of range [0, 1]"},
        BadConfig{"ObjectFollowerOutOfRange", "follower.toml", "[objects.models]\nprompt_follow_side = 8\n",
                  "objects.models.prompt_follow_side", "value 8 is out of range [16, 1024]"}),
    [](const ::testing::TestParamInfo<BadConfig>& p) { return p.param.name; });

TEST(CliConfig, AGoodFileRunsAndDefaultsPass) {
  TempDir dir;
  const std::string db = (dir / "d.db").string();
  WriteFile(dir / "good.toml", "[noop]\nwork_ms = 1\n[activity]\nmin_active_fraction = 0.3\n"
                               "[report]\nhistogram_bins = 10\n");
  const auto r = RunDoasido(
      {"init", "--db", db, "--pipeline", "noop", "--config", (dir / "good.toml").string()});
  EXPECT_EQ(r.exit_code, 0) << r.err;
}

}  // namespace
}  // namespace doasido
