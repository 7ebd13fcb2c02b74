// How artifact files travel between a parent and its shards
// (pipeline/shard.h): a shard gets its own copies, so nothing it writes can
// change the parent's files; a merge brings results home as hard links to
// the shard's files, and a second merge finds them in place.
#include <gtest/gtest.h>

#include <filesystem>

#include "core/file_text.h"
#include "db/database.h"
#include "pipeline/shard.h"
#include "tests/test_util.h"

namespace doasido::pipeline {
namespace {

namespace fs = std::filesystem;
using testing::TempDir;
using testing::WriteFile;

TEST(ShardArtifacts, ShardsAndMergesCopyNeverShareAFile) {
  TempDir dir;
  fs::create_directories(dir / "parent");
  Database parent(dir / "parent/doasido.db");
  parent.SetPipeline({"noop"});
  ClipRecord clip;
  clip.video_id = parent.UpsertVideo((dir / "video.mp4").string());
  clip.start_frame = 0;
  clip.end_frame = 9;
  const ClipId id = parent.InsertClip(clip).id;
  const fs::path rel = fs::path("artifacts") / std::to_string(id) / "stage";
  EXPECT_EQ(parent.ArtifactDir(id, "stage"), parent.root() / rel);
  WriteFile(parent.root() / rel / "before.txt", "the parent's");

  const auto shards = ShardQueue(parent, {.shards = 1, .out_dir = dir / "shards"});
  ASSERT_EQ(shards.size(), 1u);
  const fs::path shard_root = shards[0].db.parent_path();
  ASSERT_TRUE(fs::exists(shard_root / rel / "before.txt"));
  EXPECT_FALSE(fs::equivalent(shard_root / rel / "before.txt", parent.root() / rel / "before.txt"))
      << "a shard must not share the parent's files";

  WriteFile(shard_root / rel / "nested/result.txt", "the shard's");
  MergeShard(parent, shards[0].db);
  EXPECT_EQ(TryReadFile(parent.root() / rel / "nested/result.txt"), "the shard's");
  EXPECT_FALSE(fs::equivalent(shard_root / rel / "nested/result.txt",
                              parent.root() / rel / "nested/result.txt"));
  EXPECT_EQ(fs::hard_link_count(parent.root() / rel / "nested/result.txt"), 1u);
  // The shard writing its file again (a re-run) leaves the parent's alone
  // until the next merge brings the new one over whole.
  WriteFile(shard_root / rel / "nested/result.txt", "the shard's second run");
  EXPECT_EQ(TryReadFile(parent.root() / rel / "nested/result.txt"), "the shard's");
  MergeShard(parent, shards[0].db);
  EXPECT_EQ(TryReadFile(parent.root() / rel / "nested/result.txt"), "the shard's second run");
  EXPECT_EQ(fs::hard_link_count(parent.root() / rel / "nested/result.txt"), 1u);
  for (const auto& entry : fs::directory_iterator(parent.root() / "artifacts" / std::to_string(id))) {
    EXPECT_NE(entry.path().filename().string()[0], '.') << "leftover " << entry.path();
  }
}

}  // namespace
}  // namespace doasido::pipeline
