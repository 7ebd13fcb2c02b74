// Hands in still images (issue 54): a close-up where the hand fills most
// of the frame and grayscale images are found, with the side and the
// keypoints of their hand-made labels (bench/hand_labels/: real photos
// from Debian's opencv-doc and gcompris-qt-data and npm's fingerpose, and a close-up crop of a labelled real video
// frame with its labels moved by the crop, hands/labelled_stills.h); and
// the hand models' graphs are built once per process, not per landmarker
// or thread (filters/hand_models.h: the start-up tax).
#include <gtest/gtest.h>

#include <thread>

#include "filters/hand_landmarker.h"
#include "filters/hand_models.h"
#include "hands/hand_detection.h"
#include "hands/labelled_stills.h"
#include "hands/hands_config.h"
#include "test_util.h"

namespace doasido::hands {
namespace {

namespace fs = std::filesystem;

filters::HandLandmarker& Landmarker() {
  static filters::HandLandmarker landmarker(
      {.max_hands = HandsConfig{}.max_hands, .max_side = HandsConfig{}.max_side});
  return landmarker;
}

// The still's labelled hands against what DetectImage finds (the hands
// stage's and `doasido hands`' path for an image).
PckScore Score(const LabelledStill& still) {
  const DetectedFrames d = DetectImage(still.image, Landmarker());
  std::vector<PredictedHand> predicted;
  for (const HandObservation& o : d.frames.at(0)) {
    predicted.push_back({.side = o.p_right >= 0.5 ? Side::kRight : Side::kLeft, .uv = o.uv});
  }
  return ScoreFrame(still.labels, predicted);
}

// Every labelled hand found, none on the other side, and PCK@0.2 at least
// `floor` (a mirrored or swapped hand scores about 0.2, a miss 0).
void ExpectFound(const LabelledStill& still, double floor) {
  const PckScore s = Score(still);
  std::printf("%s %s: %d of %d found, PCK@0.2 %.3f, PCK@0.1 %.3f, %.1f px\n", still.name.c_str(),
              still.kind.c_str(), s.hands - s.missed, s.hands, s.Pck02(), s.Pck01(),
              s.MeanErrorPx());
  EXPECT_EQ(s.missed, 0) << still.name << " " << still.kind;
  EXPECT_EQ(s.swaps, 0) << still.name << " " << still.kind;
  EXPECT_GE(s.Pck02(), floor) << still.name << " " << still.kind;
}

class HandStills : public ::testing::Test {
 protected:
  void SetUp() override {
    std::string why;
    if (!filters::HandLandmarkerAvailable(&why)) GTEST_SKIP() << "hand models unavailable: " << why;
  }
};

// opencv-doc's handSrc.jpg: a left hand lying flat that fills the frame,
// the wrist past the border (the palm detector alone finds no hand in it);
// and Histogram_Comparison_Source_0 in gray (one channel).
TEST_F(HandStills, RealCloseUpPhotoAndGrayPhotoAreFound) {
  const fs::path photos = testing::SourceDir() / "bench/hand_labels/photos";
  const auto close_up = PhotoStills(photos / "handSrc.json");
  ExpectFound(close_up.at(0), 0.8);
  const auto open = PhotoStills(photos / "Histogram_Comparison_Source_0.json");
  ASSERT_EQ(open.at(1).image.channels(), 1);
  ExpectFound(open.at(1), 0.8);
}

// Photos that packages install elsewhere (hands/packaged_image.h):
// GCompris's back of a left hand, cut out on white inside a Qt resource
// file (gcompris-qt-data), in gray (the palm detector alone misses it), and
// fingerpose's right hand pointing up, the other fingers curled (npm). In
// gray the models call fingerpose's hand left (docs/benchmarks.md).
TEST_F(HandStills, PackagedPhotosAreFound) {
  const fs::path photos = testing::SourceDir() / "bench/hand_labels/photos";
  const auto gcompris = PhotoStills(photos / "gcompris_main_gauche_dessus_0.json");
  ASSERT_EQ(gcompris.at(1).image.channels(), 1);
  ExpectFound(gcompris.at(1), 0.8);
  ExpectFound(PhotoStills(photos / "fingerpose_nocurl.json").at(0), 0.8);
}

// asl_hand frame 0 (one right hand, labelled) cropped so that the hand's
// box spans 0.7 of the side, in colour and in gray (one channel).
TEST_F(HandStills, CloseUpOfALabelledFrameAndItsGrayVersionAreFound) {
  const HandLabels labels =
      ReadHandLabels(testing::SourceDir() / "bench/hand_labels/asl_hand.json");
  const LabelledFrame& frame = labels.frames.at(0);
  ASSERT_EQ(frame.frame, 0);
  const cv::Mat bgr = DecodeFrame(testing::SharedData() / labels.video, frame.frame);
  LabelledStill close = CloseUp(bgr, frame, 0);
  close.name = "asl_hand 0";
  ASSERT_EQ(close.labels.hands.size(), 1u);
  EXPECT_EQ(close.labels.hands[0].side, Side::kRight);
  ExpectFound(close, 0.8);
  ExpectFound(Gray(close), 0.8);
}

// The close-up's labels are the frame's moved by the crop's corner.
TEST(LabelledStills, CloseUpMovesTheLabelsWithTheCrop) {
  cv::Mat bgr(300, 400, CV_8UC3, cv::Scalar(0, 0, 0));
  LabelledFrame frame;
  LabelledHand hand;
  for (int j = 0; j < kJoints; ++j) {
    hand.uv[j] = {200 + 2 * j, 100 + 3 * j};  // box 40 x 60
    hand.visible[j] = true;
  }
  frame.hands = {hand};
  const LabelledStill close = CloseUp(bgr, frame, 0, 0.5);
  ASSERT_EQ(close.image.cols, 120);  // 60 / 0.5
  ASSERT_EQ(close.image.rows, 120);
  // Centre (220, 130): corner (160, 70).
  EXPECT_EQ(close.labels.hands.at(0).uv[0], Eigen::Vector2d(40, 30));
  EXPECT_EQ(close.labels.hands.at(0).uv[20], Eigen::Vector2d(80, 90));
  const LabelledStill gray = Gray(close);
  EXPECT_EQ(gray.image.channels(), 1);
  EXPECT_EQ(gray.kind, std::string(kStillCloseUp) + kGraySuffix);
}

// Prepared once, the graphs serve every later landmarker, on this thread
// or another: no build after the first (the start-up tax is paid before
// the first clip); two landmarkers alive at once need a second pair.
TEST_F(HandStills, GraphsAreBuiltOncePerProcess) {
  const std::string models = HandsConfig{}.models;
  ASSERT_TRUE(filters::PrepareHandModels(models));
  const int built = filters::HandModelGraphBuilds();
  ASSERT_GE(built, 1);
  ASSERT_TRUE(filters::PrepareHandModels(models));  // already there: no build
  EXPECT_EQ(filters::HandModelGraphBuilds(), built);
  const cv::Mat frame(240, 320, CV_8UC3, cv::Scalar(90, 120, 150));
  for (int i = 0; i < 2; ++i) {
    filters::HandLandmarker here({.models = models});
    here.Detect(frame);
  }
  std::thread([&] {
    filters::HandLandmarker there({.models = models});
    there.Detect(frame);
  }).join();
  EXPECT_EQ(filters::HandModelGraphBuilds(), built);
  {
    filters::HandLandmarker a({.models = models}), b({.models = models});
    a.Detect(frame);
    b.Detect(frame);
  }
  const int with_two = filters::HandModelGraphBuilds();
  EXPECT_LE(with_two, built + 1);
  filters::HandLandmarker c({.models = models}), d({.models = models});
  EXPECT_EQ(filters::HandModelGraphBuilds(), with_two);
}

}  // namespace
}  // namespace doasido::hands
