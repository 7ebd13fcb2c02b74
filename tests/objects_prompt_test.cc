// A person's object prompt (ingest/object_prompt.h): a clip list's
// object_box column carried into the clip's metadata under that one name
// and checked at load (bad rows named by line and field); the objects stage
// refusing a bad prompt by clip and field; and on real video, 02_cups'
// right hand lowering a cup onto the ball (file frames 12-40), a cup the
// models' 2D detector never finds: prompted by a box on frame 15, the cup
// is followed, and its keypoint centre lands on the hand-made labels
// (bench/object_labels/02_cups.json, frames 20 and 30); prompted the same
// way on the whole video, the track never moves onto another of its cups.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <map>

#include "core/error.h"
#include "core/error_codes.h"
#include "ingest/clip_list.h"
#include "ingest/object_prompt.h"
#include "objects/object_detection.h"
#include "objects/object_prompts.h"
#include "stages/objects_stage.h"
#include "tests/test_util.h"

namespace doasido::objects {
namespace {

using testing::SharedData;
using testing::SourceDir;
using testing::TempDir;

std::filesystem::path Cups() { return SharedData() / "videos" / "02_cups.mp4"; }

TEST(ObjectPrompt, AListRowCarriesItUnderOneNameAndBadOnesAreNamedByField) {
  TempDir dir;
  const std::string cups = Cups().string();
  testing::WriteFile(dir / "clips.csv",
                     "video,id,start_frame,end_frame,Object_Box\n" +          // 1
                         cups + ",good,12,40,\"15:288,40,180,255\"\n" +       // 2
                         cups + ",two,0,99,\"5:1,2,3,4;9:1,2,3,4:sneakers\"\n" +  // 3
                         cups + ",none,100,120,\n" +                          // 4 no prompt
                         cups + ",short,200,220,\"15:1,2,3\"\n" +             // 5 three numbers
                         cups + ",flat,221,230,\"222:1,2,0,4\"\n" +           // 6 zero width
                         cups + ",before,240,260,\"15:1,2,3,4\"\n" +          // 7 outside the span
                         cups + ",word,261,270,\"x:1,2,3,4\"\n");             // 8 no frame
  const ingest::ListReadResult r = ingest::ReadClipList(dir / "clips.csv");
  std::map<std::string, Json> meta;
  for (const ingest::ListRow& row : r.rows) meta[row.clip.external_id] = row.clip.metadata;
  ASSERT_EQ(meta.size(), 3u);
  EXPECT_EQ(meta["good"][ingest::kObjectBoxColumn], "15:288,40,180,255");
  EXPECT_FALSE(meta["good"].contains("Object_Box"));
  EXPECT_EQ(meta["two"][ingest::kObjectBoxColumn], "5:1,2,3,4;9:1,2,3,4:sneakers");
  EXPECT_FALSE(meta["none"].is_object() && meta["none"].contains(ingest::kObjectBoxColumn));
  ASSERT_EQ(r.errors.size(), 4u);
  for (const ingest::RowError& e : r.errors) EXPECT_EQ(e.field, ingest::kObjectBoxColumn) << e.Format();
  EXPECT_EQ(r.errors[0].line, 5);
  EXPECT_EQ(r.errors[1].line, 6);
  EXPECT_EQ(r.errors[2].line, 7);
  EXPECT_NE(r.errors[2].reason.find("outside the clip's frames 240-260"), std::string::npos)
      << r.errors[2].reason;
  EXPECT_EQ(r.errors[3].line, 8);

  // The seeds the stage makes of it: file frames, pixels, the default category.
  const std::vector<SeedBox> seeds = SeedsFromPrompt("5:1,2,3,4;9:10,20,30,40:sneakers", "c", "f");
  ASSERT_EQ(seeds.size(), 2u);
  EXPECT_EQ(seeds[0].frame, 5);
  EXPECT_EQ(seeds[0].category, "cup");
  EXPECT_EQ(seeds[1].category, "sneakers");
  EXPECT_EQ(seeds[1].box, cv::Rect2d(10, 20, 30, 40));
}

TEST(ObjectPrompt, TheStageRefusesABadPromptNamingClipAndField) {
  TempDir root;
  for (const std::string bad : {"15:1,2,3", "15:1,2,3,4:teapot"}) {
    ClipContext c;
    c.clip.id = 7;
    c.clip.external_id = "cups_held";
    c.clip.metadata = {{ingest::kObjectBoxColumn, bad}};
    c.artifact_dir = root / "artifacts/7/objects";
    c.video.path = Cups();
    try {
      stages::ObjectsStage().Run(c);
      ADD_FAILURE() << "accepted " << bad;
    } catch (const Error& e) {
      EXPECT_EQ(e.code(), kBadObjectBox) << bad;
      EXPECT_EQ(e.site().clip, "cups_held");
      EXPECT_EQ(e.site().field, ingest::kObjectBoxColumn);
      EXPECT_TRUE(IsPermanentError(e.code()));
    }
  }
}

// The labelled centre of the held cup on `frame` (on frames 20 and 30 the
// leftmost of the three) and the cup's height in pixels (its rims' distance).
struct Label {
  Eigen::Vector2d centre;
  double height = 0;
};
Label CupLabel(const Json& cup) {
  const auto point = [&](const char* name) {
    return Eigen::Vector2d(cup.at(name)[0].get<double>(), cup.at(name)[1].get<double>());
  };
  return {point("centre"), (point("upper") - point("lower")).norm()};
}
Label HeldCup(int frame) {
  const Json labels = Json::parse(testing::ReadFile(SourceDir() / "bench/object_labels/02_cups.json"));
  Label best{{1e9, 1e9}, 0};
  for (const Json& f : labels.at("frames")) {
    if (f.at("frame") != frame) continue;
    for (const Json& cup : f.at("cups")) {
      const Label l = CupLabel(cup);
      if (l.centre.x() < best.centre.x()) best = l;
    }
  }
  return best;
}

TEST(ObjectPrompt, APromptedHeldCupIsFollowedOntoItsLabels) {
  // 02_cups, frames 12-40: the right hand lowers a red cup onto the ball
  // (in the air on frame 15, on the table from frame ~30). The box on frame
  // 15 was drawn by eye around the cup.
  const FrameSpan span{.first_frame = 12, .frames = 29};
  ObjectsConfig config;
  config.models.categories = {"cup"};
  const std::vector<ObjectObservation> unprompted = DetectObjects(Cups(), span, config);
  EXPECT_TRUE(unprompted.empty()) << "the 2D detector now finds the red cups: the prompt is not needed";

  const std::vector<ObjectObservation> seen =
      DetectObjects(Cups(), span, config, nullptr, SeedsFromPrompt("15:288,40,180,255", "cups", "object_box"));
  std::map<int, Eigen::Vector2d> centre;  // file frame -> keypoint 0
  for (const ObjectObservation& o : seen) {
    EXPECT_EQ(o.category, "cup");
    EXPECT_EQ(o.track, seen.front().track);  // one object, one track
    centre[span.first_frame + o.frame] = o.keypoints_2d[0];
  }
  // Before, the model's own keypoints fed its next crop, shrank onto part
  // of the held cup and lost it: no frame of this span.
  EXPECT_GE(centre.size(), 20u) << "frames with keypoints of 29";
  for (const int frame : {20, 30}) {
    ASSERT_TRUE(centre.count(frame)) << "frame " << frame;
    const Label label = HeldCup(frame);
    ASSERT_GT(label.height, 100) << "frame " << frame;
    const double error = (centre[frame] - label.centre).norm() / label.height;
    // The labels' own centre is the rims' midpoint; the box's centre sits
    // within a quarter of the cup's height of it.
    EXPECT_LT(error, 0.25) << "frame " << frame << ": " << centre[frame].transpose() << " vs label "
                           << label.centre.transpose();
  }
}

// The held cup's labelled centre and height on each labelled frame up to
// `last`: on frame 20 the leftmost cup, then on each next labelled frame
// the cup nearest its centre before (the labels name no cup; up to frame
// 90 the held cup is set down and stays clear of the others).
std::map<int, Label> HeldCupUpTo(int last) {
  const Json labels = Json::parse(testing::ReadFile(SourceDir() / "bench/object_labels/02_cups.json"));
  std::map<int, Label> held{{20, HeldCup(20)}};
  for (const Json& f : labels.at("frames")) {
    const int frame = f.at("frame");
    if (frame <= 20 || frame > last) continue;
    const Eigen::Vector2d before = held.rbegin()->second.centre;
    Label best{{1e9, 1e9}, 0};
    for (const Json& cup : f.at("cups")) {
      const Label l = CupLabel(cup);
      if ((l.centre - before).norm() < (best.centre - before).norm()) best = l;
    }
    held[frame] = best;
  }
  return held;
}

TEST(ObjectPrompt, ThePromptedCupIsNeverFollowedOntoAnotherCupOverTheWholeVideo) {
  // The demo's prompt (frame 15, the cup in the right hand) on all 300
  // frames of 02_cups, three identical red cups moved about by two hands:
  // on frame 100 the cups cross behind a hand and the labels no longer tell
  // which is the prompted one. The track must sit on the held cup on every
  // frame within 5 of a labelled one up to 90 where it has keypoints, and
  // end before frame 100, since past it nothing shows it is still on the
  // right cup. (Without the jump guard, --max-jump 10, the median-flow box
  // follows the hand onto the middle cup from frame 83.) (A
  // follower that lost the cup and drifted onto another one, as MIL on a
  // frame shrunk to a 56-px box did, carried on to frame ~260.)
  const FrameSpan span{.first_frame = 0, .frames = 300};
  ObjectsConfig config;
  config.models.categories = {"cup"};
  const std::vector<ObjectObservation> seen =
      DetectObjects(Cups(), span, config, nullptr, SeedsFromPrompt("15:288,40,180,255", "cups", "object_box"));
  ASSERT_FALSE(seen.empty());
  const int prompted = seen.front().track;
  ASSERT_LE(seen.front().frame, 20) << "the prompted track has keypoints within 5 frames of its box";
  const std::map<int, Label> held = HeldCupUpTo(90);
  int last = 0, checked = 0;
  for (const ObjectObservation& o : seen) {
    if (o.track != prompted) continue;
    last = std::max(last, static_cast<int>(o.frame));
    // The nearest labelled frame within 5: a quarter of the cup's height on
    // it, half (the cup moves up to ~40 px in 5 frames; the next cup is
    // >= 240 px away) on the frames about it.
    const auto label = std::min_element(held.begin(), held.end(), [&](const auto& a, const auto& b) {
      return std::abs(a.first - o.frame) < std::abs(b.first - o.frame);
    });
    const int apart = std::abs(label->first - o.frame);
    if (apart > 5) continue;
    checked += apart == 0;
    const double error = (o.keypoints_2d[0] - label->second.centre).norm() / label->second.height;
    EXPECT_LT(error, apart == 0 ? 0.25 : 0.5) << "frame " << o.frame << ": " << o.keypoints_2d[0].transpose()
                                              << " vs the held cup at " << label->second.centre.transpose()
                                              << " on frame " << label->first;
  }
  EXPECT_GE(checked, 4) << "labelled frames with the prompted track";  // measured: 20, 30, 40, 50, 60
  EXPECT_LT(last, 100) << "the prompted track lasted past the cups' crossing, to frame " << last;
}

}  // namespace
}  // namespace doasido::objects
