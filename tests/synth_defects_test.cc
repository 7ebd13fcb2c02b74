// Every defect kind asked for appears, and its recorded frames are visible
// in the decoded video: cuts and fades in the frame statistics, camera
// motion in Lucas-Kanade feature tracks matching the recorded homographies,
// out-of-frame spans in the masks, stillness in the pixel differences.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <numeric>
#include <opencv2/calib3d.hpp>
#include <opencv2/imgproc.hpp>
#include <opencv2/video/tracking.hpp>
#include <opencv2/videoio.hpp>

#include "recon/bundle/bundle.h"
#include "synth/generator.h"
#include "tests/test_util.h"

namespace doasido::synth {
namespace {

namespace fs = std::filesystem;

class DefectsTest : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    dir_ = new testing::TempDir();
    SynthConfig cfg;
    cfg.width = 320;
    cfg.height = 240;
    cfg.frames = 48;
    cfg.seed = 21;
    // Other seeds can be tried without rebuilding.
    if (const char* seed = std::getenv("DOASIDO_SYNTH_TEST_SEED")) cfg.seed = std::stoull(seed);
    cfg.clips = kDefectKindCount;
    cfg.track_points = 8;
    cfg.mix =
        "clean=1,cut=1,fade=1,black=1,pan=1,shake=1,zoom=1,out_of_frame=1,object_out=1,"
        "no_contact=1,static=1";
    summary_ = new DatasetSummary(GenerateDataset(cfg, dir_->path()));
  }
  static void TearDownTestSuite() {
    delete summary_;
    delete dir_;
  }

  // The ground truth of the one clip of `kind`.
  static Json Gt(const std::string& kind) {
    for (const auto& e : fs::directory_iterator(dir_->path() / "gt")) {
      Json j = Json::parse(testing::ReadFile(e.path()));
      if (j["kind"] == kind) return j;
    }
    ADD_FAILURE() << "no clip of kind " << kind;
    return Json();
  }
  static std::vector<cv::Mat> Frames(const Json& gt) {
    cv::VideoCapture cap((dir_->path() / gt["video"].get<std::string>()).string(), cv::CAP_FFMPEG);
    std::vector<cv::Mat> out;
    for (cv::Mat f; cap.read(f);) out.push_back(f.clone());
    EXPECT_EQ(static_cast<int>(out.size()), gt["frames"].get<int>());
    return out;
  }
  static recon::ClipBundle Bundle(const Json& gt) {
    return recon::ReadBundle(dir_->path() / "bundles" / gt["clip"].get<std::string>());
  }
  static const Json& Defect(const Json& gt, const std::string& kind) {
    for (const Json& d : gt["defects"]) {
      if (d["kind"] == kind) return d;
    }
    ADD_FAILURE() << "defect " << kind << " not recorded";
    static const Json none = Json{{"start", 0}, {"end", 0}, {"params", Json::object()}};
    return none;
  }

  static testing::TempDir* dir_;
  static DatasetSummary* summary_;
};
testing::TempDir* DefectsTest::dir_ = nullptr;
DatasetSummary* DefectsTest::summary_ = nullptr;

// PySceneDetect ContentDetector-style score: mean |delta| of H, S, V.
double ContentScore(const cv::Mat& a, const cv::Mat& b) {
  cv::Mat ha, hb, d;
  cv::cvtColor(a, ha, cv::COLOR_BGR2HSV);
  cv::cvtColor(b, hb, cv::COLOR_BGR2HSV);
  cv::absdiff(ha, hb, d);
  const cv::Scalar m = cv::mean(d);
  return (m[0] + m[1] + m[2]) / 3;
}

double MeanGray(const cv::Mat& f) {
  cv::Mat g;
  cv::cvtColor(f, g, cv::COLOR_BGR2GRAY);
  return cv::mean(g)[0];
}

// Background motion measured as in Data-Juicer's camera-motion filter:
// Shi-Tomasi corners (200, 0.01, 7) on frame t-1 away from hands and object,
// pyramidal Lucas-Kanade to frame t, RANSAC homography. Returns the largest
// distance (px) between the measured and the recorded homography's
// displacement over a grid of background pixels, and the largest recorded
// displacement there; {inf, 0} when too few tracks.
std::pair<double, double> FlowResidual(const std::vector<cv::Mat>& frames,
                                       const recon::ClipBundle& b, const Json& gt, int t) {
  cv::Mat g0, g1;
  cv::cvtColor(frames[t - 1], g0, cv::COLOR_BGR2GRAY);
  cv::cvtColor(frames[t], g1, cv::COLOR_BGR2GRAY);
  cv::Mat fg = b.mask_object[t - 1] | b.mask_hand_left[t - 1] | b.mask_hand_right[t - 1] |
               b.mask_object[t] | b.mask_hand_left[t] | b.mask_hand_right[t];
  cv::dilate(fg, fg, cv::Mat(), cv::Point(-1, -1), 6);
  cv::Mat allowed = fg == 0;
  std::vector<cv::Point2f> p0, p1;
  cv::goodFeaturesToTrack(g0, p0, 200, 0.01, 7, allowed);
  if (p0.size() < 20) return {1e9, 0};
  std::vector<unsigned char> status;
  std::vector<float> err;
  // Background motion is a few pixels per frame; a shallow pyramid keeps the
  // coarse levels from being dragged by fast hands next to the features.
  cv::calcOpticalFlowPyrLK(g0, g1, p0, p1, status, err, cv::Size(15, 15), 1);
  std::vector<cv::Point2f> a, c;
  for (size_t i = 0; i < p0.size(); ++i) {
    if (status[i]) a.push_back(p0[i]), c.push_back(p1[i]);
  }
  if (a.size() < 20) return {1e9, 0};
  cv::Mat inliers;
  const cv::Mat hm = cv::findHomography(a, c, cv::RANSAC, 3.0, inliers);
  if (hm.empty()) return {1e9, 0};
  const auto& h = gt["per_frame"][t]["H_prev"];
  Mat3 recorded;
  for (int i = 0; i < 9; ++i) recorded(i / 3, i % 3) = h[i].get<double>();
  std::vector<double> res, motion;
  for (size_t i = 0; i < a.size(); ++i) {
    if (!inliers.at<std::uint8_t>(static_cast<int>(i))) continue;
    const Vec3 r = recorded * Vec3(a[i].x, a[i].y, 1);
    res.push_back((r.head<2>() / r.z() - Vec2(c[i].x, c[i].y)).norm());
    motion.push_back((r.head<2>() / r.z() - Vec2(a[i].x, a[i].y)).norm());
  }
  if (res.size() < 0.5 * a.size() || res.size() < 15) {
    ADD_FAILURE() << "frame " << t << ": only " << res.size() << " of " << a.size()
                  << " tracks agree on one homography";
    return {1e9, 0};
  }
  std::nth_element(res.begin(), res.begin() + res.size() / 2, res.end());
  std::nth_element(motion.begin(), motion.begin() + motion.size() / 2, motion.end());
  return {res[res.size() / 2], motion[motion.size() / 2]};
}

TEST_F(DefectsTest, EveryKindAppears) {
  for (int k = 0; k < kDefectKindCount; ++k) {
    const std::string name = DefectName(static_cast<DefectKind>(k));
    EXPECT_EQ(summary_->defect_counts.at(name), 1) << name;
    const Json gt = Gt(name);
    if (name != "clean") {
      EXPECT_FALSE(gt["defects"].empty()) << name;
      Defect(gt, name);
    } else {
      EXPECT_TRUE(gt["defects"].empty());
    }
  }
  const Json s = Json::parse(testing::ReadFile(dir_->path() / "summary.json"));
  EXPECT_EQ(s["clips"], kDefectKindCount);
}

TEST_F(DefectsTest, CutIsTheLargestFrameChange) {
  const Json gt = Gt("cut");
  const auto frames = Frames(gt);
  const int cut = Defect(gt, "cut")["start"].get<int>();
  std::vector<double> score(frames.size(), 0.0);
  for (size_t t = 1; t < frames.size(); ++t) score[t] = ContentScore(frames[t - 1], frames[t]);
  const auto max_it = std::max_element(score.begin(), score.end());
  EXPECT_EQ(max_it - score.begin(), cut);
  std::vector<double> rest(score.begin() + 1, score.end());
  std::nth_element(rest.begin(), rest.begin() + rest.size() / 2, rest.end());
  EXPECT_GT(score[cut], 5 * rest[rest.size() / 2]);
}

TEST_F(DefectsTest, CrossFadeFramesAreBlendsOfBothShots) {
  const Json gt = Gt("fade");
  const auto frames = Frames(gt);
  const Json& d = Defect(gt, "fade");
  const int s = d["start"].get<int>(), e = d["end"].get<int>();
  const cv::Mat& a = frames[s - 1];
  const cv::Mat& b = frames[e + 1];
  double ab = cv::norm(a, b, cv::NORM_L1) / a.total();
  for (int t = s; t <= e; ++t) {
    const double w = gt["per_frame"][t]["blend"].get<double>();
    EXPECT_GT(w, 0.0);
    EXPECT_LT(w, 1.0);
    cv::Mat predicted;
    cv::addWeighted(a, 1 - w, b, w, 0, predicted);
    const double err = cv::norm(frames[t], predicted, cv::NORM_L1) / a.total();
    EXPECT_LT(err, 0.5 * ab) << "frame " << t;
  }
  // Outside the span frames are not blends.
  EXPECT_EQ(gt["per_frame"][s - 1]["blend"].get<double>(), 0.0);
}

TEST_F(DefectsTest, FadesReachBlack) {
  const Json gt = Gt("black");
  const auto frames = Frames(gt);
  const int T = static_cast<int>(frames.size());
  EXPECT_LT(MeanGray(frames[0]), 12);  // PySceneDetect ThresholdDetector level
  EXPECT_LT(MeanGray(frames[T - 1]), 12);
  EXPECT_GT(MeanGray(frames[T / 2]), 40);
  for (const Json& d : gt["defects"]) {
    const int s = d["start"].get<int>(), e = d["end"].get<int>();
    const bool in = d["params"]["direction"] == "in";
    for (int t = s + 1; t <= e; ++t) {
      if (in) {
        EXPECT_GT(MeanGray(frames[t]), MeanGray(frames[t - 1]) - 1);
      } else {
        EXPECT_LT(MeanGray(frames[t]), MeanGray(frames[t - 1]) + 1);
      }
    }
  }
}

TEST_F(DefectsTest, CameraMotionMatchesRecordedHomographies) {
  for (const std::string kind : {"pan", "shake", "zoom"}) {
    SCOPED_TRACE(kind);
    const Json gt = Gt(kind);
    const auto frames = Frames(gt);
    const recon::ClipBundle b = Bundle(gt);
    const Json& d = Defect(gt, kind);
    int moving = 0, checked = 0;
    for (int t = d["start"].get<int>() + 1; t <= d["end"].get<int>(); t += 2) {
      const auto [res, mag] = FlowResidual(frames, b, gt, t);
      if (res > 1e8) continue;
      ++checked;
      moving += mag > 1.0;
      EXPECT_LT(res, 0.5) << kind << " frame " << t << " recorded motion " << mag;
    }
    EXPECT_GE(checked, 5) << kind;
    EXPECT_GE(moving, kind == "zoom" ? 3 : 5) << kind;
  }
  // A pan moves the background by the recorded amount at the image centre.
  const Json pan = Gt("pan");
  const int mid =
      (Defect(pan, "pan")["start"].get<int>() + Defect(pan, "pan")["end"].get<int>()) / 2;
  const double rate = Defect(pan, "pan")["params"]["rad_per_frame"].get<double>();
  const double fx = pan["per_frame"][mid]["K"][0].get<double>();
  EXPECT_NEAR(pan["per_frame"][mid]["bg_dx"].get<double>(), fx * std::tan(rate),
              0.05 * std::abs(fx * rate));
  // A clean clip's background does not move.
  const Json clean = Gt("clean");
  const auto frames = Frames(clean);
  const recon::ClipBundle b = Bundle(clean);
  for (int t = 5; t < static_cast<int>(frames.size()); t += 10) {
    const auto [res, mag] = FlowResidual(frames, b, clean, t);
    EXPECT_LT(mag, 1e-9);
    EXPECT_LT(res, 0.3);
  }
}

TEST_F(DefectsTest, OutOfFrameSpansHaveEmptyMasks) {
  for (const std::string kind : {"out_of_frame", "object_out"}) {
    const Json gt = Gt(kind);
    const recon::ClipBundle b = Bundle(gt);
    const Json& d = Defect(gt, kind);
    const int s = d["start"].get<int>(), e = d["end"].get<int>();
    EXPECT_GE(e - s + 1, 3) << kind;
    const bool right = d["params"]["side"] == "right";
    const auto& hand_masks = right ? b.mask_hand_right : b.mask_hand_left;
    for (int t = s; t <= e; ++t) {
      EXPECT_EQ(cv::countNonZero(hand_masks[t]), 0) << kind << " frame " << t;
      if (kind == "object_out") {
        EXPECT_EQ(cv::countNonZero(b.mask_object[t]), 0) << t;
      }
    }
    // Seen before leaving and after coming back.
    EXPECT_GT(cv::countNonZero(hand_masks[std::max(0, s - 8)]), 0) << kind;
    EXPECT_GT(cv::countNonZero(hand_masks[b.frames - 1]), 0) << kind;
  }
}

TEST_F(DefectsTest, NoContactClipNeverTouches) {
  const Json gt = Gt("no_contact");
  const Json& d = Defect(gt, "no_contact");
  const double gap = d["params"]["min_gap_m"].get<double>();
  EXPECT_GT(gap, 0.003);
  EXPECT_LT(gap, 0.08);
  EXPECT_GT(d["end"].get<int>() - d["start"].get<int>(), 5);
  for (const Json& f : gt["per_frame"]) {
    EXPECT_FALSE(f["contact"][0].get<bool>());
    EXPECT_FALSE(f["contact"][1].get<bool>());
  }
  // A clean clip does touch.
  int touching = 0;
  const Json clean = Gt("clean");
  for (const Json& f : clean["per_frame"])
    touching += f["contact"][0].get<bool>() || f["contact"][1].get<bool>();
  EXPECT_GT(touching, 5);
}

// Fraction of pixels changing by more than 30 levels between frames.
double ChangedFraction(const cv::Mat& a, const cv::Mat& b) {
  cv::Mat d, g;
  cv::absdiff(a, b, d);
  cv::cvtColor(d, g, cv::COLOR_BGR2GRAY);
  return static_cast<double>(cv::countNonZero(g > 30)) / g.total();
}

TEST_F(DefectsTest, StaticClipHasNoActivity) {
  const auto still = Frames(Gt("static"));
  const auto clean = Frames(Gt("clean"));
  double still_max = 0, clean_max = 0;
  for (size_t t = 1; t < still.size(); ++t)
    still_max = std::max(still_max, ChangedFraction(still[t - 1], still[t]));
  for (size_t t = 1; t < clean.size(); ++t)
    clean_max = std::max(clean_max, ChangedFraction(clean[t - 1], clean[t]));
  EXPECT_LT(still_max, 0.001);
  EXPECT_GT(clean_max, 0.003);
}

}  // namespace
}  // namespace doasido::synth
