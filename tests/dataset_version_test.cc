// Dataset versions without a database: split assignment by video, the
// manifest's JSON, `verify` against changed bytes, and `diff` reasons on
// hand-made manifests.
#include <fstream>
#include <map>
#include <set>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "core/error.h"
#include "dataset/splits.h"
#include "dataset/version_diff.h"
#include "dataset/version_files.h"
#include "tests/test_util.h"

namespace doasido::dataset {
namespace {

using ::testing::HasSubstr;
using doasido::testing::TempDir;
using doasido::testing::WriteFile;

std::vector<Episode> Episodes(int videos, int per_video) {
  std::vector<Episode> out;
  for (int v = 0; v < videos; ++v) {
    for (int k = 0; k < per_video + v % 3; ++k) {
      Episode e;
      e.clip_id = static_cast<std::int64_t>(out.size()) + 1;
      e.id = "clip-" + std::to_string(e.clip_id);
      e.video_key = "/videos/v" + std::to_string(v) + ".mp4";
      out.push_back(e);
    }
  }
  return out;
}

TEST(Splits, NoVideoInTwoSplitsAndSharesFollowTheFractions) {
  std::vector<Episode> episodes = Episodes(60, 2);
  const SplitFractions fractions = ParseSplits("train=0.8,val=0.1,test=0.1");
  AssignSplits(episodes, fractions, 7);
  std::map<std::string, std::set<std::string>> splits_of_video;
  std::map<std::string, int> count;
  for (const Episode& e : episodes) {
    splits_of_video[e.video_key].insert(e.split);
    count[e.split]++;
  }
  for (const auto& [video, splits] : splits_of_video) EXPECT_EQ(splits.size(), 1u) << video;
  const double n = static_cast<double>(episodes.size());
  EXPECT_NEAR(count["train"] / n, 0.8, 0.03);
  EXPECT_NEAR(count["val"] / n, 0.1, 0.03);
  EXPECT_NEAR(count["test"] / n, 0.1, 0.03);
}

TEST(Splits, SameSeedSameSplitsOtherSeedOthers) {
  std::vector<Episode> a = Episodes(40, 1), b = Episodes(40, 1), c = Episodes(40, 1);
  const SplitFractions f = ParseSplits("train=0.5,test=0.5");
  AssignSplits(a, f, 1);
  AssignSplits(b, f, 1);
  AssignSplits(c, f, 2);
  int differ = 0;
  for (size_t i = 0; i < a.size(); ++i) {
    EXPECT_EQ(a[i].split, b[i].split);
    differ += a[i].split != c[i].split;
  }
  EXPECT_GT(differ, 0);
}

TEST(Splits, BadTextNamesTheOptionAndPart) {
  for (const char* bad : {"train=0.8,val=0.1", "train=0.8,train=0.2", "train=x", "Train=1",
                          "train=1.5,val=-0.5", "train"}) {
    try {
      ParseSplits(bad);
      FAIL() << bad;
    } catch (const Error& e) {
      EXPECT_EQ(e.code(), "bad_option") << bad;
      EXPECT_EQ(e.site().field, "--split") << bad;
    }
  }
}

Manifest SampleManifest() {
  Manifest m;
  m.name = "demo";
  m.version = "v1";
  m.created_at = 1700000000;
  m.tool_version = "0.1.0";
  m.tool_revision = "abc";
  m.database = "/tmp/x.db";
  m.selection = Selection::kAll;
  m.split_fractions = {{"train", 1.0}};
  m.trajectory_stage = "retarget_kinematic";
  for (int i = 0; i < 3; ++i) {
    Episode e;
    e.id = "clip-00000" + std::to_string(i + 1);
    e.index = i;
    e.clip_id = i + 1;
    e.external_id = "c" + std::to_string(i + 1);
    e.video = e.video_key = "/v/" + std::to_string(i) + ".mp4";
    e.start_frame = 10 * i;
    e.end_frame = 10 * i + 9;
    e.split = "train";
    e.trajectory_stage = m.trajectory_stage;
    e.stages = {{"interaction", "h1", "pass", "", "stage"},
                {"retarget_kinematic", "k1", "pass", "", "stage"}};
    m.episodes.push_back(e);
    m.files.push_back({"episodes/" + e.id + "/trajectory.json", "00", 2});
  }
  m.excluded.push_back({4, "c4", {"interaction", "h1", "reject", "no_interaction", "stage"},
                        "interaction: reject (no_interaction)"});
  return m;
}

TEST(Manifest, JsonRoundTrip) {
  Manifest m = SampleManifest();
  m.episodes[1].verification = Verification{"alice", 1700000100.5, "ok"};
  m.episodes[2].start_frame.reset();
  const Manifest back = ManifestFromJson(ToJson(m));
  EXPECT_EQ(ToJson(back), ToJson(m));
  ASSERT_TRUE(back.episodes[1].verification);
  EXPECT_EQ(back.episodes[1].verification->reviewer, "alice");
  EXPECT_FALSE(back.episodes[2].start_frame);
}

TEST(Manifest, MissingMemberIsNamed) {
  Json j = ToJson(SampleManifest());
  j["episodes"][1].erase("split");
  try {
    ManifestFromJson(j);
    FAIL();
  } catch (const Error& e) {
    EXPECT_EQ(e.code(), "bad_manifest");
    EXPECT_EQ(e.site().field, "episodes[1].split");
  }
}

TEST(VerifyVersion, NamesChangedMissingAndExtraFiles) {
  TempDir dir;
  WriteFile(dir / "episodes/a/trajectory.json", "{\"qpos\": [1, 2, 3]}");
  WriteFile(dir / "episodes/b/trajectory.json", "{\"qpos\": [4]}");
  WriteFile(dir / "playbook/report.json", "{}");
  Manifest m = SampleManifest();
  m.files = HashFiles(dir.path());
  ASSERT_EQ(m.files.size(), 3u);
  WriteManifest(m, dir.path());
  EXPECT_TRUE(VerifyVersion(dir.path()).empty());

  // One byte changed, same size.
  std::fstream f((dir / "episodes/a/trajectory.json").string(),
                 std::ios::in | std::ios::out | std::ios::binary);
  f.seekp(11);
  f.put('7');
  f.close();
  auto problems = VerifyVersion(dir.path());
  ASSERT_EQ(problems.size(), 1u);
  EXPECT_EQ(problems[0].path, "episodes/a/trajectory.json");
  EXPECT_THAT(problems[0].what, HasSubstr("SHA-256"));

  std::filesystem::remove(dir / "playbook/report.json");
  WriteFile(dir / "episodes/b/extra.txt", "x");
  problems = VerifyVersion(dir.path());
  std::map<std::string, std::string> by_path;
  for (const auto& p : problems) by_path[p.path] = p.what;
  EXPECT_EQ(by_path.size(), 3u);
  EXPECT_EQ(by_path["playbook/report.json"], "missing");
  EXPECT_EQ(by_path["episodes/b/extra.txt"], "not in the manifest");
}

TEST(DiffVersions, ReasonsForEachKindOfChange) {
  const Manifest a = SampleManifest();
  Manifest b = a;
  b.version = "v2";
  // Clip 1 re-thresholded out at interaction; clip 2 verified by a person;
  // clip 3 unchanged; clip 4 (excluded in v1) back in under new parameters.
  b.episodes.erase(b.episodes.begin());
  b.excluded = {{1, "c1", {"interaction", "h2", "reject", "no_interaction", "rethreshold"},
                 "interaction: reject (no_interaction) by rethreshold"}};
  b.episodes[0].verification = Verification{"bob", 5, ""};
  b.episodes[0].stages[0].param_hash = "h2";  // re-thresholded, verdict kept: not a reason
  Episode back = a.episodes[2];
  back.clip_id = 4;
  back.id = "clip-000004";
  back.external_id = "c4";
  back.stages[0] = {"interaction", "h2", "pass", "", "rethreshold"};
  b.episodes.push_back(back);
  b.files = {{"episodes/clip-000002/trajectory.json", "00", 2},
             {"episodes/clip-000003/trajectory.json", "ff", 2},
             {"episodes/clip-000004/trajectory.json", "00", 2}};

  std::map<std::int64_t, EpisodeChange> got;
  for (const EpisodeChange& c : DiffVersions(a, b)) got[c.clip_id] = c;
  ASSERT_EQ(got.size(), 4u);
  EXPECT_EQ(got[1].kind, EpisodeChange::Kind::kRemoved);
  EXPECT_THAT(got[1].reasons[0], HasSubstr("interaction: re-threshold, new parameters (h1 -> h2)"));
  EXPECT_THAT(got[1].reasons[0], HasSubstr("pass -> reject (no_interaction)"));
  EXPECT_EQ(got[2].kind, EpisodeChange::Kind::kChanged);
  EXPECT_EQ(got[2].reasons, std::vector<std::string>{"verified by bob"});
  EXPECT_EQ(got[3].kind, EpisodeChange::Kind::kChanged);
  EXPECT_EQ(got[3].reasons, std::vector<std::string>{"files changed"});
  EXPECT_EQ(got[4].kind, EpisodeChange::Kind::kAdded);
  EXPECT_THAT(got[4].reasons[0], HasSubstr("reject (no_interaction) -> pass"));
  EXPECT_TRUE(DiffVersions(a, a).empty());
}

}  // namespace
}  // namespace doasido::dataset
