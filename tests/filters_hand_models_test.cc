// The hand models' native runtime (our TFLite reader + XNNPACK) against the
// reference, TFLite's own WebAssembly runtime, on every real sample video
// (../shared/data/videos): the same hands, keypoints within half a pixel,
// the palm detector's boxes within a pixel. And the reader on bad files.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <algorithm>
#include <cstring>
#include <fstream>

#include "core/error.h"
#include "filters/hand_landmarker.h"
#include "filters/hand_models.h"
#include "filters/learned_hand_detector.h"
#include "filters/tflite_model.h"
#include "test_util.h"
#include "video/video_decoder.h"

namespace doasido::filters {
namespace {

std::vector<std::filesystem::path> RealVideos() {
  std::vector<std::filesystem::path> videos;
  for (const auto& e : std::filesystem::directory_iterator(testing::SharedData() / "videos")) {
    const std::string ext = e.path().extension().string();
    if (ext == ".mp4" || ext == ".avi") videos.push_back(e.path());
  }
  std::sort(videos.begin(), videos.end());
  return videos;
}

// A few frames of `video` at analysis size, as the analysis pass sees them.
std::vector<cv::Mat> SomeFrames(const std::filesystem::path& video) {
  DecoderOptions options;
  options.last_frame = 60;
  VideoDecoder decoder(video, options);
  std::vector<cv::Mat> frames;
  AnalysisFrame frame;
  for (int i = 0; decoder.Next(&frame); ++i) {
    if (i % 30 == 0) frames.push_back(frame.bgr.clone());
  }
  return frames;
}

double MaxCornerGap(const cv::Rect2d& a, const cv::Rect2d& b) {
  return std::max({std::abs(a.x - b.x), std::abs(a.y - b.y), std::abs(a.br().x - b.br().x),
                   std::abs(a.br().y - b.br().y)});
}

// The two runtimes on the models `models` (kModelsFull, ...).
void ExpectNativeEqualsWebAssembly(const std::string& models) {
  std::string why;
  if (!WasmHandModelsAvailable(&why)) GTEST_SKIP() << "no reference runtime: " << why;
  HandLandmarker native({.backend = kBackendNative, .models = models});
  ASSERT_STREQ(native.backend(), kBackendNative) << native.note();
  HandLandmarker wasm({.backend = kBackendWasm, .models = models});
  int hands = 0, palms = 0;
  double worst_keypoint = 0, worst_palm = 0;
  for (const std::filesystem::path& video : RealVideos()) {
    native.Reset();
    wasm.Reset();
    for (const cv::Mat& frame : SomeFrames(video)) {
      const auto a = native.Detect(frame), b = wasm.Detect(frame);
      ASSERT_EQ(a.size(), b.size()) << video.filename();
      for (std::size_t h = 0; h < a.size(); ++h) {
        ++hands;
        EXPECT_NEAR(a[h].score, b[h].score, 0.01) << video.filename();
        for (int k = 0; k < kHandKeypoints; ++k) {
          const double gap = std::max(std::abs(a[h].keypoints[k].x - b[h].keypoints[k].x),
                                      std::abs(a[h].keypoints[k].y - b[h].keypoints[k].y));
          worst_keypoint = std::max(worst_keypoint, gap);
          EXPECT_LE(gap, 0.5) << video.filename() << " hand " << h << " keypoint " << k;
          EXPECT_NEAR(a[h].world[k].x, b[h].world[k].x, 1e-3) << video.filename();
        }
      }
      const auto pa = native.DetectPalms(frame), pb = wasm.DetectPalms(frame);
      ASSERT_EQ(pa.size(), pb.size()) << video.filename();
      for (std::size_t p = 0; p < pa.size(); ++p) {
        ++palms;
        worst_palm = std::max(worst_palm, MaxCornerGap(pa[p].box, pb[p].box));
        EXPECT_LE(MaxCornerGap(pa[p].box, pb[p].box), 1.0) << video.filename();
      }
    }
  }
  std::printf("%s: %d hands, %d palms compared; largest gaps: keypoint %.4f px, palm box %.4f px\n",
              models.c_str(), hands, palms, worst_keypoint, worst_palm);
  // Most sample videos show hands: a comparison of nothing would prove nothing.
  EXPECT_GE(hands, 15);
  EXPECT_GE(palms, 10);
}

TEST(HandModels, NativeEqualsWebAssemblyOnEveryRealVideo) {
  ExpectNativeEqualsWebAssembly(kModelsFull);
}

// The filters' default (the full palm detector, the lite landmark model).
TEST(HandModels, LiteLandmarkNativeEqualsWebAssemblyOnEveryRealVideo) {
  ExpectNativeEqualsWebAssembly(kModelsLiteLandmark);
}

TEST(HandModels, LiteModelsNativeEqualsWebAssemblyOnEveryRealVideo) {
  ExpectNativeEqualsWebAssembly(kModelsLite);
}

// CheckConfig refuses `config` naming `field`.
void ExpectRefusedNaming(const LearnedDetectorConfig& config, const std::string& field) {
  try {
    CheckConfig(config, "filters_analyze.learned_detector");
    ADD_FAILURE() << "accepted";
  } catch (const Error& e) {
    EXPECT_EQ(e.code(), "bad_config");
    EXPECT_NE(std::string(e.what()).find(field), std::string::npos) << e.what();
  }
}

TEST(HandModels, TheModelsNamesPickTheirFilesAndAnUnknownOneIsRefused) {
  EXPECT_EQ(PalmModelFile(kModelsFull), "palm_detection_full.tflite");
  EXPECT_EQ(LandmarkModelFile(kModelsFull), "hand_landmark_full.tflite");
  EXPECT_EQ(PalmModelFile(kModelsLite), "palm_detection_lite.tflite");
  EXPECT_EQ(LandmarkModelFile(kModelsLite), "hand_landmark_lite.tflite");
  EXPECT_EQ(PalmModelFile(kModelsLiteLandmark), "palm_detection_full.tflite");
  EXPECT_EQ(LandmarkModelFile(kModelsLiteLandmark), "hand_landmark_lite.tflite");
  LearnedDetectorConfig config;
  config.models = "tiny";
  ExpectRefusedNaming(config, "models");
  EXPECT_THROW(MakeHandModels(kBackendNative, "clip", true, nullptr, "tiny"), Error);
}

std::vector<std::uint8_t> LandmarkModelBytes() {
  std::ifstream in(MediapipeHandsDir() / "hand_landmark_full.tflite", std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

TEST(TfliteReader, ReadsTheLandmarkModelsShapesAndFoldsItsFp16Weights) {
  std::string why;
  if (!HandModelFilesAvailable(&why)) GTEST_SKIP() << why;
  const std::vector<std::uint8_t> bytes = LandmarkModelBytes();
  const TfliteModel m = ReadTfliteModel(bytes.data(), bytes.size(), "hand_landmark_full.tflite");
  ASSERT_EQ(m.inputs.size(), 1u);
  EXPECT_EQ(m.tensors[m.inputs[0]].shape, (std::vector<int>{1, 224, 224, 3}));
  ASSERT_EQ(m.outputs.size(), 4u);
  EXPECT_EQ(m.tensors[m.outputs[0]].shape, (std::vector<int>{1, 63}));
  for (const TfliteOperator& o : m.operators) EXPECT_NE(o.op, TfliteOp::kDequantize);
  // The first convolution: 24 filters of 3 x 3 x 3, fp16 in the file, finite
  // and not all zero once converted.
  const TfliteOperator& conv = m.operators.front();
  ASSERT_EQ(conv.op, TfliteOp::kConv2d);
  const TfliteTensor& filter = m.tensors[conv.inputs[1]];
  EXPECT_EQ(filter.shape, (std::vector<int>{24, 3, 3, 3}));
  ASSERT_EQ(filter.data.size(), 24u * 27u);
  double energy = 0;
  for (float w : filter.data) {
    ASSERT_TRUE(std::isfinite(w));
    energy += w * w;
  }
  EXPECT_GT(energy, 0.1);
  EXPECT_EQ(conv.stride_w, 2);
}

TEST(TfliteReader, TruncatedOrForeignFilesAreRefusedNamingTheFile) {
  std::string why;
  if (!HandModelFilesAvailable(&why)) GTEST_SKIP() << why;
  const std::vector<std::uint8_t> bytes = LandmarkModelBytes();
  for (const std::size_t size : {bytes.size() / 2, std::size_t{100}, std::size_t{6}}) {
    try {
      ReadTfliteModel(bytes.data(), size, "cut.tflite");
      ADD_FAILURE() << "read " << size << " bytes of a model";
    } catch (const Error& e) {
      EXPECT_EQ(e.code(), "bad_model");
      EXPECT_NE(std::string(e.what()).find("cut.tflite"), std::string::npos) << e.what();
    }
  }
  std::vector<std::uint8_t> foreign = bytes;
  std::memcpy(foreign.data() + 4, "ABCD", 4);
  EXPECT_THROW(ReadTfliteModel(foreign.data(), foreign.size(), "foreign.bin"), Error);
}

TEST(TfliteReader, HalfPrecisionConvertsExactly) {
  EXPECT_EQ(HalfToFloat(0x3c00), 1.0f);
  EXPECT_EQ(HalfToFloat(0xc000), -2.0f);
  EXPECT_EQ(HalfToFloat(0x7bff), 65504.0f);          // largest half
  EXPECT_EQ(HalfToFloat(0x0001), std::ldexp(1.0f, -24));  // smallest subnormal
  EXPECT_EQ(HalfToFloat(0x3555), 0.333251953125f);
  EXPECT_EQ(HalfToFloat(0x8000), -0.0f);
  EXPECT_TRUE(std::isinf(HalfToFloat(0x7c00)));
}

TEST(HandModels, AnUnknownBackendIsRefusedWhenLoaded) {
  LearnedDetectorConfig config;
  config.backend = "gpu";
  ExpectRefusedNaming(config, "backend");
}

}  // namespace
}  // namespace doasido::filters
