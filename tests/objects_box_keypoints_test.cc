// The objects' 2D box keypoints (objects/box_tracker.h): the SSD anchors and
// decoding against the graph's published options, the crop geometry, the
// detector's hash check, the native runtime against TFLite's WebAssembly
// runtime on real crops, the cups of ../shared/data/videos/02_cups.mp4, and
// renders of the built-in mug whose true box is known exactly.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>

#include <opencv2/imgproc.hpp>

#include "core/config.h"
#include "core/error.h"
#include "eval/mug_mesh.h"
#include "objects/box_detector.h"
#include "objects/box_tracker.h"
#include "objects/hand_proposals.h"
#include "objects/objects_file.h"
#include "objects/objects_in_video.h"
#include "synth/render.h"
#include "test_util.h"
#include "video/video_decoder.h"

namespace doasido::objects {
namespace {

namespace fs = std::filesystem;

bool ModelsOr(std::string* why) { return ObjectronModelFilesAvailable(why); }

TEST(SsdAnchors, AreTheGraphsAnchors) {
  const std::vector<SsdAnchor>& a = SsdAnchors();
  ASSERT_EQ(a.size(), static_cast<std::size_t>(kDetectorAnchors));
  // Lowest layer (19 x 19 cells, 3 per cell): scale 0.1 ratio 1, then 0.2 ratio 2 and 0.5.
  EXPECT_NEAR(a[0].cx, 0.5 / 19, 1e-6);
  EXPECT_NEAR(a[0].w, 0.1, 1e-6);
  EXPECT_NEAR(a[1].w, 0.2 * std::sqrt(2.0), 1e-6);
  EXPECT_NEAR(a[1].h, 0.2 / std::sqrt(2.0), 1e-6);
  EXPECT_NEAR(a[3].cx, 1.5 / 19, 1e-6);
  // Second layer (10 x 10, 6 per cell) starts after 1083: scale 0.35, its
  // sixth anchor sqrt(0.35 * 0.5).
  EXPECT_NEAR(a[1083].cx, 0.05, 1e-6);
  EXPECT_NEAR(a[1083].w, 0.35, 1e-6);
  EXPECT_NEAR(a[1083 + 3].w, 0.35 * std::sqrt(3.0), 1e-5);
  EXPECT_NEAR(a[1083 + 5].w, std::sqrt(0.35 * 0.5), 1e-6);
  // The last cell: one, centred, scale 0.95 and sqrt(0.95 * 1).
  EXPECT_NEAR(a.back().cx, 0.5, 1e-6);
  EXPECT_NEAR(a[kDetectorAnchors - 6].w, 0.95, 1e-6);
  EXPECT_NEAR(a.back().w, std::sqrt(0.95), 1e-6);
}

std::vector<std::string> Labels() {
  std::vector<std::string> l(kDetectorClasses, "Other");
  l[0] = "???";
  l[4] = "Person";
  l[12] = "Mug";
  l[13] = "Coffee cup";
  l[19] = "Footwear";
  return l;
}

TEST(DecodeDetections, KeepsAllowedLabelsAboveTheScoreAndSuppressesOverlaps) {
  DetectorOutput out;
  out.boxes.assign(kDetectorAnchors * 4, 0.f);
  out.logits.assign(kDetectorAnchors * kDetectorClasses, -10.f);
  const auto set = [&](int anchor, int cls, float logit) { out.logits[anchor * kDetectorClasses + cls] = logit; };
  const int a = 1083 + 6 * 44;  // second layer, cell (4, 4), ratio 1
  set(a, 13, 2.0f);             // a coffee cup, score 0.88
  set(a + 5, 12, 1.0f);         // a mug on the same cell, larger box: overlaps, lower score
  set(100, 4, 5.0f);            // a person: not an allowed label
  set(200, 19, 3.0f);           // footwear: allowed only with the sneakers model
  set(300, 13, -0.1f);          // a cup below 0.5
  set(a, 0, 9.0f);              // class 0 is ignored even when it scores best
  // An offset of (1, 1, 0, 0) moves the box by a tenth of the anchor.
  out.boxes[a * 4 + 0] = 1.0f;
  out.boxes[a * 4 + 1] = 1.0f;
  const std::vector<DetectedBox> cups = DecodeDetections(out, Labels(), {"cup"}, 0.5, 0.5, 5);
  ASSERT_EQ(cups.size(), 1u);
  EXPECT_EQ(cups[0].category, "cup");
  EXPECT_EQ(cups[0].label, "Coffee cup");
  EXPECT_NEAR(cups[0].score, 1 / (1 + std::exp(-2.0)), 1e-6);
  const SsdAnchor& anchor = SsdAnchors()[a];
  EXPECT_NEAR(cups[0].box.x + cups[0].box.width / 2, anchor.cx + 0.1 * anchor.w, 1e-6);
  EXPECT_NEAR(cups[0].box.y + cups[0].box.height / 2, anchor.cy + 0.1 * anchor.h, 1e-6);
  EXPECT_NEAR(cups[0].box.width, anchor.w, 1e-6);
  const std::vector<DetectedBox> both = DecodeDetections(out, Labels(), {"cup", "sneakers"}, 0.5, 0.5, 5);
  ASSERT_EQ(both.size(), 2u);
  EXPECT_EQ(both[0].label, "Footwear");
  EXPECT_EQ(both[0].category, "sneakers");
  // With suppression off the mug survives too.
  EXPECT_EQ(DecodeDetections(out, Labels(), {"cup"}, 0.5, 1.0, 5).size(), 2u);
}

std::array<Eigen::Vector2d, kBoxKeypoints> BoxPoints(double angle_deg) {
  // A 40 x 80 px box (front face 10 px lower-right) about (300, 200), its up axis turned.
  const double a = angle_deg * M_PI / 180, c = std::cos(a), s = std::sin(a);
  std::array<Eigen::Vector2d, kBoxKeypoints> p;
  p[0] = {300, 200};
  for (int k = 1; k < kBoxKeypoints; ++k) {
    const int b = k - 1;
    const double x = (b & 4 ? 20 : -20) + (b & 1 ? 5 : -5), y = (b & 2 ? -40 : 40) + (b & 1 ? 5 : -5);
    // Clockwise on screen by `a`: (x, y) -> (c x - s y, s x + c y).
    p[k] = {300 + c * x - s * y, 200 + s * x + c * y};
  }
  return p;
}

TEST(BoxCrops, FollowTheBoxsUpAxisAndMapBackToTheFrame) {
  const BoxCrop upright = CropFromKeypoints(BoxPoints(0), 1.5);
  EXPECT_NEAR(upright.rotation, 0, 1e-9);
  EXPECT_NEAR(upright.side, 1.5 * 90, 1e-9);  // the extent's long side: 80 + 2 * 5
  EXPECT_NEAR(upright.cx, 300, 1e-9);
  const BoxCrop turned = CropFromKeypoints(BoxPoints(30), 1.5);
  EXPECT_NEAR(turned.rotation, 30 * M_PI / 180, 1e-9);
  // A dot in the frame lands in the crop where CropToFrame says.
  cv::Mat rgb(400, 600, CV_8UC3, cv::Scalar(0, 0, 0));
  cv::circle(rgb, {330, 170}, 2, cv::Scalar(255, 255, 255), -1);
  std::vector<float> input;
  LandmarkInput(rgb, turned, &input);
  cv::Mat crop(kBoxInputSize, kBoxInputSize, CV_32FC3, input.data());
  cv::Mat grey;
  cv::cvtColor(crop, grey, cv::COLOR_RGB2GRAY);
  cv::Moments m = cv::moments(grey);
  ASSERT_GT(m.m00, 0);
  const double u = m.m10 / m.m00 + 0.5, v = m.m01 / m.m00 + 0.5;  // continuous
  const cv::Matx23d map = CropToFrame(turned);
  EXPECT_NEAR(map(0, 0) * u + map(0, 1) * v + map(0, 2), 330.5, 0.3);
  EXPECT_NEAR(map(1, 0) * u + map(1, 1) * v + map(1, 2), 170.5, 0.3);
}

TEST(ObjectronModels, TheDetectorMustMatchItsRecordedHash) {
  std::string why;
  if (!ModelsOr(&why)) GTEST_SKIP() << why;
  testing::TempDir tmp;
  const fs::path copy = tmp / "node_modules/@mediapipe/objectron";
  fs::create_directories(copy);
  for (const auto& e : fs::directory_iterator(ObjectronDir())) {
    fs::create_symlink(e.path(), copy / e.path().filename());
  }
  const std::string packed = "objectron_solution_packed_assets.data";
  fs::remove(copy / packed);
  fs::copy_file(ObjectronDir() / packed, copy / packed);
  const auto [begin, end] = PackedAssetRange(copy, "object_detection_ssd_mobilenetv2_oidv4_fp16.tflite");
  {
    std::fstream f(copy / packed, std::ios::in | std::ios::out | std::ios::binary);
    f.seekp(static_cast<std::streamoff>((begin + end) / 2));
    f.put('\x5a');
  }
  const char* old = std::getenv("DOASIDO_NPM_DIR");
  const std::string kept = old ? old : "";
  setenv("DOASIDO_NPM_DIR", tmp.path().c_str(), 1);
  try {
    ObjectronModels models({"cup"}, "clip");
    ADD_FAILURE() << "a detector with a changed byte loaded";
  } catch (const Error& e) {
    EXPECT_EQ(e.code(), "object_detector_unavailable");
    EXPECT_NE(std::string(e.what()).find(kDetectorSha256), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find(packed), std::string::npos) << e.what();
  }
  if (old) setenv("DOASIDO_NPM_DIR", kept.c_str(), 1); else unsetenv("DOASIDO_NPM_DIR");
  ObjectronModels models({"cup"}, "clip");  // the installed one loads
  EXPECT_EQ(models.labels().at(13), "Coffee cup");
  EXPECT_EQ(models.labels().at(12), "Mug");
}

// A few frames of 02_cups at the tracker's size.
std::vector<cv::Mat> CupFrames(int every, int last) {
  DecoderOptions options{.analysis_size = 640, .last_frame = last, .skip_loop_filter = false};
  VideoDecoder decoder(testing::SharedData() / "videos/02_cups.mp4", options);
  std::vector<cv::Mat> frames;
  AnalysisFrame frame;
  for (int i = 0; decoder.Next(&frame); ++i) {
    if (i % every == 0) frames.push_back(frame.bgr.clone());
  }
  return frames;
}

// Runs tests/objectron_reference.js on `inputs` (each size*size*3); the
// outputs, per input, in the order of the model's output names.
std::vector<float> WebAssemblyOutputs(const fs::path& model, std::size_t begin, std::size_t end,
                                      int size, const std::vector<std::vector<float>>& inputs) {
  testing::TempDir tmp;
  {
    std::ofstream f(tmp / "in.f32", std::ios::binary);
    for (const auto& in : inputs) f.write(reinterpret_cast<const char*>(in.data()), in.size() * 4);
  }
  const std::string command = "NODE_PATH=" + (ObjectronDir().parent_path().parent_path()).string() +
                              " node " + (testing::SourceDir() / "tests/objectron_reference.js").string() +
                              " " + model.string() + " " + std::to_string(begin) + " " + std::to_string(end) +
                              " " + std::to_string(size) + " " + (tmp / "in.f32").string() + " " +
                              (tmp / "out.f32").string();
  testing::ShellOk(command);
  std::ifstream f(tmp / "out.f32", std::ios::binary);
  std::vector<char> bytes{std::istreambuf_iterator<char>(f), std::istreambuf_iterator<char>()};
  std::vector<float> out(bytes.size() / 4);
  std::memcpy(out.data(), bytes.data(), out.size() * 4);
  return out;
}

TEST(ObjectronModels, NativeEqualsWebAssemblyOnRealFrames) {
  std::string why;
  if (!ModelsOr(&why)) GTEST_SKIP() << why;
  if (std::system("node --version > /dev/null 2>&1") != 0) GTEST_SKIP() << "no node";
  ObjectronModels models({"cup"}, "02_cups");
  const std::vector<cv::Mat> frames = CupFrames(60, 299);
  std::vector<std::vector<float>> detector_in, box_in;
  std::vector<DetectorOutput> detector_native;
  std::vector<BoxLandmarkOutput> box_native;
  for (const cv::Mat& bgr : frames) {
    cv::Mat rgb;
    cv::cvtColor(bgr, rgb, cv::COLOR_BGR2RGB);
    detector_in.emplace_back();
    DetectorInput(rgb, &detector_in.back());
    models.Detect(detector_in.back().data(), &detector_native.emplace_back());
    // Crops about the frame's middle cup region and a turned one.
    for (const BoxCrop& crop : {BoxCrop{rgb.cols * 0.5, rgb.rows * 0.45, 160, 0},
                                BoxCrop{rgb.cols * 0.35, rgb.rows * 0.5, 200, 0.3}}) {
      box_in.emplace_back();
      LandmarkInput(rgb, crop, &box_in.back());
      models.Landmarks("cup", box_in.back().data(), &box_native.emplace_back());
    }
  }
  const auto [begin, end] = PackedAssetRange(ObjectronDir(), "object_detection_ssd_mobilenetv2_oidv4_fp16.tflite");
  const std::vector<float> det = WebAssemblyOutputs(ObjectronDir() / "objectron_solution_packed_assets.data",
                                                    begin, end, kDetectorInputSize, detector_in);
  const std::size_t per = kDetectorAnchors * (4 + kDetectorClasses);
  ASSERT_EQ(det.size(), per * frames.size());
  double worst_box = 0, worst_logit = 0;
  for (std::size_t f = 0; f < frames.size(); ++f) {
    for (std::size_t i = 0; i < kDetectorAnchors * 4u; ++i) {
      worst_box = std::max(worst_box, double(std::abs(det[f * per + i] - detector_native[f].boxes[i])));
    }
    for (std::size_t i = 0; i < kDetectorAnchors * std::size_t{kDetectorClasses}; ++i) {
      worst_logit = std::max(worst_logit, double(std::abs(det[f * per + kDetectorAnchors * 4 + i] -
                                                          detector_native[f].logits[i])));
    }
  }
  const std::vector<float> box = WebAssemblyOutputs(ObjectronDir() / "object_detection_3d_cup.tflite", 0, 0,
                                                    kBoxInputSize, box_in);
  ASSERT_EQ(box.size(), 19 * box_in.size());
  double worst_keypoint = 0, worst_presence = 0;
  for (std::size_t c = 0; c < box_in.size(); ++c) {
    worst_presence = std::max(worst_presence, double(std::abs(box[19 * c] - box_native[c].presence)));
    for (int k = 0; k < 18; ++k) {
      worst_keypoint = std::max(worst_keypoint, double(std::abs(box[19 * c + 1 + k] - box_native[c].keypoints[k])));
    }
  }
  std::printf("%zu frames, %zu crops: largest gaps: detector box offset %.2e, logit %.2e; "
              "keypoint %.2e px (of 224), presence %.2e\n",
              frames.size(), box_in.size(), worst_box, worst_logit, worst_keypoint, worst_presence);
  EXPECT_LT(worst_box, 1e-2);
  EXPECT_LT(worst_logit, 1e-2);
  EXPECT_LT(worst_keypoint, 0.05);
  EXPECT_LT(worst_presence, 1e-3);
}

// The centre of the box's top (corners 3 4 7 8) or bottom (1 2 5 6) face.
Eigen::Vector2d FaceCentre(const ObjectObservation& o, bool top) {
  Eigen::Vector2d sum = Eigen::Vector2d::Zero();
  for (int k = 1; k < kBoxKeypoints; ++k) {
    if ((((k - 1) & 2) != 0) == top) sum += o.keypoints_2d[k] / 4;
  }
  return sum;
}

Eigen::Vector2d Point(const Json& xy) { return {xy.at(0).get<double>(), xy.at(1).get<double>()}; }

// 02_cups, frames 0-89: the detector misses the red plastic cups (no track
// starts without a seed); seeded with the two table cups as a person boxed
// them on frame 0 (from the hand-made labels of bench/object_labels/), the
// cup model tracks them, and its keypoints land on the labelled cups: each
// labelled frame (0, 10, ..., 80, checked by eye: every cup in view) with a
// track, the centre and the top and bottom faces' centres against the
// labelled centre and upper and lower rims.
TEST(BoxTracker, TracksTheSeededRedCupsOf02CupsOntoTheHandMadeLabels) {
  std::string why;
  if (!ModelsOr(&why)) GTEST_SKIP() << why;
  const Json labels = Json::parse(testing::ReadFile(testing::SourceDir() / "bench/object_labels/02_cups.json"));
  BoxKeypointsConfig config;
  config.categories = {"cup"};
  BoxTracker tracker(config, "02_cups");
  const fs::path video = testing::SharedData() / "videos/02_cups.mp4";
  const DecoderOptions span{.last_frame = 89};
  const DetectedObjects unseeded = ObjectsInVideo(video, span, config.max_side, tracker);
  int unseeded_frames = 0;
  for (const auto& f : unseeded.frames) unseeded_frames += !f.empty();
  std::vector<SeedBox> seeds;
  for (const Json& cup : labels.at("frames").at(0).at("cups")) {
    const Eigen::Vector2d up = Point(cup.at("upper")), low = Point(cup.at("lower"));
    const double h = low.y() - up.y();  // a person's box: the cup's height, 0.8 of it wide
    seeds.push_back({.frame = 0, .category = "cup",
                     .box = cv::Rect2d(up.x() - 0.4 * h, up.y() - 0.05 * h, 0.8 * h, 1.1 * h)});
  }
  const DetectedObjects seeded = ObjectsInVideo(video, span, config.max_side, tracker, {}, seeds);
  int seeded_frames = 0;
  for (const auto& f : seeded.frames) seeded_frames += !f.empty();
  double centre = 0, top = 0, bottom = 0, height = 0;
  int n = 0;
  for (const Json& frame : labels.at("frames")) {
    const int f = frame.at("frame");
    if (f > 89) continue;
    for (const ObjectObservation& o : seeded.frames.at(f)) {
      const Json* best = nullptr;
      for (const Json& cup : frame.at("cups")) {
        if (!best || (Point(cup.at("centre")) - o.keypoints_2d[0]).norm() <
                         (Point(best->at("centre")) - o.keypoints_2d[0]).norm()) {
          best = &cup;
        }
      }
      ASSERT_NE(best, nullptr);
      centre += (Point(best->at("centre")) - o.keypoints_2d[0]).norm();
      top += (Point(best->at("upper")) - FaceCentre(o, true)).norm();
      bottom += (Point(best->at("lower")) - FaceCentre(o, false)).norm();
      height += (Point(best->at("upper")) - Point(best->at("lower"))).norm();
      ++n;
    }
  }
  ASSERT_GT(n, 0);
  std::printf("02_cups 0-89: %d frames with a cup unseeded, %d seeded; %d labelled cups matched: "
              "mean error centre %.1f px, top face %.1f px, bottom face %.1f px (cups %.0f px tall)\n",
              unseeded_frames, seeded_frames, n, centre / n, top / n, bottom / n, height / n);
  EXPECT_EQ(unseeded_frames, 0);  // the detector's miss, stated: no "Coffee cup" or "Mug" box
  EXPECT_GE(seeded_frames, 70);   // measured: 85 (the right cup to frame 89, the left to 53)
  EXPECT_GE(n, 8);
  EXPECT_LT(centre / n, 0.1 * height / n);  // measured 11.4 px of 213
  EXPECT_LT(top / n, 0.15 * height / n);
}

// One render of the built-in mug standing on the table, seen from the side
// `view` (0-3), with its true box: the mesh's bounds (handle included), and
// the camera.
struct MugView {
  synth::FrameState st;
  synth::RenderedFrame r;
  std::array<Eigen::Vector2d, kBoxKeypoints> truth;  // the bounds' 9 keypoints, pixel-corner origin
  Eigen::Vector3d lo, hi;                            // the bounds, mug frame (axis +z)
};

MugView RenderMugView(int view) {
  static const TriMesh mug = retarget::MakeMug();
  MugView v;
  v.lo = mug.Min();
  v.hi = mug.Max();
  synth::World world;
  world.style = synth::RandomStyle(3);
  v.st.camera = {640, 480, 560, 560, 319.5, 239.5};
  const double a = view * M_PI / 2 + 0.4;
  v.st.camera_from_world = synth::LookAt(Vec3(0.3 * std::sin(a), -0.3 * std::cos(a), 0.22), Vec3(0, 0, 0.045));
  v.st.object_pose = Pose::Identity();
  v.r = synth::RenderFrame(world, mug, v.st);
  const auto project = [&](const Eigen::Vector3d& p) {
    return Eigen::Vector2d(v.st.camera.Project(v.st.camera_from_world * (v.st.object_pose * p)) +
                           Eigen::Vector2d(0.5, 0.5));  // to pixel-corner coordinates
  };
  v.truth[0] = project((v.lo + v.hi) / 2);
  for (int k = 1; k < kBoxKeypoints; ++k) {
    const int b = k - 1;  // (x, up, front) bits; the mug's up is its +z
    v.truth[k] = project({b & 4 ? v.hi.x() : v.lo.x(), b & 1 ? v.hi.y() : v.lo.y(), b & 2 ? v.hi.z() : v.lo.z()});
  }
  return v;
}

// The model's box on a mug view: the detector's, else a seed of the true
// box's extent, as a person would draw it. Empty when the model sees none.
std::vector<ObjectObservation> MugBox(BoxTracker& tracker, const MugView& v, bool* detected) {
  tracker.Reset();
  std::vector<ObjectObservation> seen = tracker.Track(v.r.bgr, 0);
  *detected = !seen.empty();
  if (seen.empty()) {
    double x1 = 1e9, y1 = 1e9, x2 = -1e9, y2 = -1e9;
    for (const Eigen::Vector2d& p : v.truth) {
      x1 = std::min(x1, p.x()), y1 = std::min(y1, p.y()), x2 = std::max(x2, p.x()), y2 = std::max(y2, p.y());
    }
    tracker.Reset();
    tracker.Seed("cup", cv::Rect2d(x1, y1, x2 - x1, y2 - y1));
    seen = tracker.Track(v.r.bgr, 0);
  }
  return seen;
}

// Renders of the built-in mug (eval/mug_mesh.h) standing on the table,
// seen from four sides: the true box (the mesh's bounds, handle included)
// projected; the model's keypoints against it: the centre, and the corners
// under the best of the box's 8 relabellings that keep its up axis (the
// model cannot tell a mug's front from its back).
TEST(BoxTracker, FindsTheRenderedMugAndStatesItsKeypointError) {
  std::string why;
  if (!ModelsOr(&why)) GTEST_SKIP() << why;
  BoxKeypointsConfig config;
  config.categories = {"cup"};
  BoxTracker tracker(config, "mug");
  int found = 0, detected = 0;
  double centre = 0, corners = 0, size = 0;
  for (int view = 0; view < 4; ++view) {
    const MugView v = RenderMugView(view);
    const auto& truth = v.truth;
    bool by_detector = false;
    const std::vector<ObjectObservation> seen = MugBox(tracker, v, &by_detector);
    detected += by_detector;
    if (seen.empty()) continue;
    ++found;
    const ObjectObservation& o = seen.front();
    double best = 1e18;
    for (int flip = 0; flip < 8; ++flip) {  // x and front mirrored, x and front swapped
      double sum = 0;
      for (int k = 1; k < kBoxKeypoints; ++k) {
        int b = k - 1, x = (b >> 2) & 1, up = (b >> 1) & 1, front = b & 1;
        if (flip & 1) x ^= 1;
        if (flip & 2) front ^= 1;
        if (flip & 4) std::swap(x, front);
        sum += (o.keypoints_2d[(x << 2 | up << 1 | front) + 1] - truth[k]).norm();
      }
      best = std::min(best, sum / 8);
    }
    const double diagonal = (truth[1] - truth[8]).norm();
    centre += (o.keypoints_2d[0] - truth[0]).norm() / diagonal;
    corners += best / diagonal;
    size += diagonal;
  }
  std::printf("rendered mug, 4 views: %d found (%d by the detector); mean error over the box's "
              "projected diagonal (%.0f px): centre %.3f, corners %.3f\n",
              found, detected, found ? size / found : 0.0, found ? centre / found : 0.0,
              found ? corners / found : 0.0);
  // Measured: 4 of 4 found (2 by the detector), centre 0.149, corners 0.260
  // of the diagonal: the models were trained on real photos, not renders.
  ASSERT_GE(found, 3);
  EXPECT_LT(centre / found, 0.25);
  EXPECT_LT(corners / found, 0.4);
}

// The boxes beside a hand: a 3 x 3 grid about the grasp point (the mean of
// the thumb, index and middle fingertips), offset palm lengths apart, each
// size palm lengths wide; none for a hand too small to hold anything.
TEST(HandProposals, GridAboutTheGraspPointInPalmLengths) {
  HandPoints2d hand;
  hand.fill(Eigen::Vector2d(0, 0));
  hand[0] = {100, 300};   // wrist
  hand[9] = {100, 250};   // middle finger's base: palm 50 px
  hand[4] = {190, 200};
  hand[8] = {200, 210};
  hand[12] = {210, 190};  // grasp point (200, 200)
  const std::vector<cv::Rect2d> boxes = HandProposals(hand, {.sizes = {1.6, 2.4}, .offset = 0.5});
  ASSERT_EQ(boxes.size(), 18u);
  std::vector<std::pair<double, double>> centres;
  for (size_t i = 0; i < boxes.size(); ++i) {
    const double side = i < 9 ? 80 : 120;
    EXPECT_DOUBLE_EQ(boxes[i].width, side);
    EXPECT_DOUBLE_EQ(boxes[i].height, side);
    centres.emplace_back(boxes[i].x + side / 2, boxes[i].y + side / 2);
  }
  for (int dy = -1; dy <= 1; ++dy) {
    for (int dx = -1; dx <= 1; ++dx) {
      const auto c = centres[(dy + 1) * 3 + dx + 1];
      EXPECT_NEAR(c.first, 200 + 25 * dx, 1e-9);
      EXPECT_NEAR(c.second, 200 + 25 * dy, 1e-9);
    }
  }
  EXPECT_EQ(HandProposals(hand, {.sizes = {1.6}, .offset = 0}).size(), 1u);
  hand[9] = {100, 295};  // a 5-px palm
  EXPECT_TRUE(HandProposals(hand, {}).empty());
}

// With the detector shut (no score reaches 1) and no seed, a hand whose
// fingertips are on the rendered mug starts its track: the mug found from
// the hand alone, its centre on the mug but rougher than from a seed (as on
// real video: docs/object_models.md "Looking beside the hands").
TEST(BoxTracker, FindsTheRenderedMugBesideAHand) {
  std::string why;
  if (!ModelsOr(&why)) GTEST_SKIP() << why;
  BoxKeypointsConfig config;
  config.categories = {"cup"};
  config.min_detection_score = 1.0;
  config.hand_proposals = true;
  BoxTracker tracker(config, "mug");
  int found = 0;
  double centre = 0;
  for (int view = 0; view < 4; ++view) {
    const MugView v = RenderMugView(view);
    const double height = (v.truth[3] - v.truth[1]).norm();  // a left edge of the box, bottom to top
    HandPoints2d hand;
    hand.fill(v.truth[0]);  // every fingertip on the mug's centre
    hand[0] = v.truth[0] + Eigen::Vector2d(height, 0);  // the wrist beside it, a palm length of
    hand[9] = v.truth[0] + Eigen::Vector2d(0.4 * height, 0);  // 0.6 of the mug's height
    tracker.Reset();
    EXPECT_TRUE(tracker.Track(v.r.bgr, 0).empty()) << "view " << view << ": the detector is shut";
    tracker.Reset();
    tracker.NearHands({hand});
    const std::vector<ObjectObservation> seen = tracker.Track(v.r.bgr, 0);
    if (seen.empty()) continue;
    ++found;
    centre += (seen.front().keypoints_2d[0] - v.truth[0]).norm() / (v.truth[1] - v.truth[8]).norm();
  }
  std::printf("rendered mug beside a hand: %d of 4 views found, centre error %.3f of the box's diagonal\n", found,
              found ? centre / found : 0.0);
  // Measured: 4 of 4, centre 0.370 of the diagonal (0.149 from a seed of
  // the true box).
  ASSERT_GE(found, 3);
  EXPECT_LT(centre / found, 0.5);
}

// A held object the model loses for a frame (here a blank frame) and a
// hand box finds again is one track (hand_rejoin_frames); with rejoining
// off it is a new one.
TEST(BoxTracker, AHandsBoxContinuesTheTrackItLost) {
  std::string why;
  if (!ModelsOr(&why)) GTEST_SKIP() << why;
  const MugView v = RenderMugView(0);
  const double height = (v.truth[3] - v.truth[1]).norm();
  HandPoints2d hand;
  hand.fill(v.truth[0]);
  hand[0] = v.truth[0] + Eigen::Vector2d(height, 0);
  hand[9] = v.truth[0] + Eigen::Vector2d(0.4 * height, 0);
  const cv::Mat blank(v.r.bgr.size(), CV_8UC3, cv::Scalar(128, 128, 128));
  for (int rejoin : {30, 0}) {
    BoxKeypointsConfig config;
    config.categories = {"cup"};
    config.min_detection_score = 1.0;  // the detector shut
    config.hand_proposals = true;
    config.hand_proposal_every = 1;
    config.hand_rejoin_frames = rejoin;
    BoxTracker tracker(config, "mug");
    tracker.NearHands({hand});
    const std::vector<ObjectObservation> first = tracker.Track(v.r.bgr, 0);
    ASSERT_EQ(first.size(), 1u);
    EXPECT_TRUE(tracker.Track(blank, 1).empty());
    tracker.NearHands({hand});
    const std::vector<ObjectObservation> again = tracker.Track(v.r.bgr, 2);
    ASSERT_EQ(again.size(), 1u);
    if (rejoin > 0) {
      EXPECT_EQ(again[0].track, first[0].track);
    } else {
      EXPECT_NE(again[0].track, first[0].track);
    }
  }
}

// What `doasido objects` writes for the mug views (objects/objects_file.h):
// the model's keypoints lifted with the renders' exact K and the cup's size
// prior (no hands: scale_assumed). Against the truth: the centre (the
// mesh's bounds' centre, camera frame), the box's up axis against the mug's
// axis (a cup's turn about it is not observed), the height and the
// diameter (the body's, 0.08 m; the prior is an 11 oz mug, 0.082 x 0.095).
TEST(ObjectsFile, LiftsTheRenderedMugAndStatesItsErrors) {
  std::string why;
  if (!ModelsOr(&why)) GTEST_SKIP() << why;
  ObjectsConfig config;
  config.models.categories = {"cup"};
  BoxTracker tracker(config.models, "mug");
  int lifted = 0;
  double centre = 0, depth = 0, axis = 0, height = 0, diameter = 0, distance = 0;
  for (int view = 0; view < 4; ++view) {
    const MugView v = RenderMugView(view);
    bool by_detector = false;
    DetectedObjects d{.width = 640, .height = 480};
    d.frames.push_back(MugBox(tracker, v, &by_detector));
    if (d.frames[0].empty()) continue;
    const Mat3 K = v.st.camera.K();
    const Json j = ObjectsFileJson(d, K, config);
    ASSERT_EQ(j.at("frames").size(), 1u);
    const Json& o = j.at("frames").at(0).at("objects").at(0);
    ASSERT_FALSE(o.at("center_camera").is_null());
    EXPECT_TRUE(o.at("scale_assumed").get<bool>());
    const Vec3 c(o["center_camera"][0], o["center_camera"][1], o["center_camera"][2]);
    Mat3 R;
    for (int r = 0; r < 3; ++r) {
      for (int k = 0; k < 3; ++k) R(r, k) = o["rotation_camera"][r][k];
    }
    const Vec3 size(o["size_m"][0], o["size_m"][1], o["size_m"][2]);
    const Vec3 true_centre = v.st.camera_from_world * (v.st.object_pose * Vec3((v.lo + v.hi) / 2));
    const Vec3 true_axis = v.st.camera_from_world.R() * v.st.object_pose.R() * Vec3::UnitZ();
    ++lifted;
    distance += true_centre.norm();
    centre += (c - true_centre).norm();
    depth += std::abs(c.z() - true_centre.z());
    axis += std::acos(std::clamp(R.col(1).dot(true_axis), -1.0, 1.0));
    height += std::abs(size.y() - (v.hi.z() - v.lo.z()));
    diameter += std::abs(size.x() - 2 * retarget::MugShape{}.radius);
    EXPECT_NEAR((R.transpose() * R - Mat3::Identity()).norm(), 0, 1e-6) << "view " << view;
  }
  ASSERT_GE(lifted, 3);
  std::printf("rendered mug lifted, %d views at %.3f m: mean error of the centre %.3f m (along the depth %.3f), "
              "of the axis %.1f deg, of the height %.3f m, of the diameter %.3f m\n",
              lifted, distance / lifted, centre / lifted, depth / lifted, axis / lifted * 180 / M_PI,
              height / lifted, diameter / lifted);
  // Measured: 4 views, centre 0.020 m off (0.017 along the depth) at 0.35 m,
  // axis 2.6 deg, height 0.008 m, diameter 0.004 m. The size is the prior's
  // scale on the lifted proportions (the prior's height is the mug's), so
  // the size errors are the proportions' and the depth error the scale's.
  EXPECT_LT(centre / lifted, 0.05);
  EXPECT_LT(axis / lifted, 10 * M_PI / 180);
  EXPECT_LT(height / lifted, 0.02);
  EXPECT_LT(diameter / lifted, 0.02);
}

}  // namespace
}  // namespace doasido::objects
