#include <gtest/gtest.h>
#include <cstdio>
#include <cmath>
#include <opencv2/imgproc.hpp>
#include "objects/box_detector.h"
#include "objects/box_tracker.h"
#include "test_util.h"
#include "video/video_decoder.h"
TEST(Dump, Grid) {
  using namespace doasido; using namespace doasido::objects;
  ObjectronModels models({"cup"}, "x");
  for (const char* video : {"02_cups.mp4", "bedroom.mp4", "03_blocks.mp4", "laptop_trackpad.mp4"}) {
  DecoderOptions options{.analysis_size = 640, .skip_loop_filter = false};
  VideoDecoder decoder(doasido::testing::SharedData() / "videos" / video, options);
  AnalysisFrame frame;
  for (int i = 0; decoder.Next(&frame); ++i) {
    if (i % 100) continue;
    cv::Mat rgb; cv::cvtColor(frame.bgr, rgb, cv::COLOR_BGR2RGB);
    std::printf("%s frame %d:\n", video, i);
    for (double side : {120.0, 180.0, 270.0}) {
      for (double cy = side / 2; cy <= rgb.rows - side / 4; cy += side / 2) {
        std::printf("  side %3.0f y %3.0f:", side, cy);
        for (double cx = side / 2; cx <= rgb.cols - side / 4; cx += side / 2) {
          std::vector<float> b; LandmarkInput(rgb, BoxCrop{cx, cy, side, 0}, &b);
          BoxLandmarkOutput lo; models.Landmarks("cup", b.data(), &lo);
          std::printf(" %s", lo.presence >= 0.99 ? "X" : lo.presence >= 0.5 ? "o" : ".");
        }
        std::printf("\n");
      }
    }
  }
  }
  std::printf("landmark ms per run %.2f\n", models.landmark_ms() / models.landmark_runs());
}
