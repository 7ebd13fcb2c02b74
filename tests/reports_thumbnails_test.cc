// Thumbnails with overlays, on small videos with known content: a hard cut
// at a known frame, a box touching the border, a known image shift for the
// motion tracks, and unreadable videos.
#include <gtest/gtest.h>

#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <opencv2/videoio.hpp>
#include <random>

#include "reports/thumbnails.h"
#include "tests/test_util.h"

namespace doasido {
namespace {

using reports::MakeThumbnail;
using reports::Thumbnail;
using reports::ThumbnailOptions;
using reports::ThumbnailRequest;
using testing::TempDir;

cv::Mat Texture(int w, int h, std::uint32_t seed) {
  cv::Mat small(h / 8, w / 8, CV_8UC1);
  std::mt19937 rng(seed);
  for (int y = 0; y < small.rows; ++y) {
    for (int x = 0; x < small.cols; ++x) small.at<unsigned char>(y, x) = rng() % 256;
  }
  cv::Mat big;
  cv::resize(small, big, {w, h}, 0, 0, cv::INTER_CUBIC);
  cv::GaussianBlur(big, big, {3, 3}, 0);
  return big;
}

// 40 frames of 160x120: frames 0-19 blue, 20-39 red (a hard cut at 20).
std::filesystem::path WriteCutVideo(const std::filesystem::path& path) {
  cv::VideoWriter writer(path.string(), cv::VideoWriter::fourcc('M', 'J', 'P', 'G'), 20,
                         {160, 120});
  EXPECT_TRUE(writer.isOpened());
  for (int t = 0; t < 40; ++t) {
    cv::Mat frame(120, 160, CV_8UC3, t < 20 ? cv::Scalar(200, 40, 40) : cv::Scalar(40, 40, 200));
    writer.write(frame);
  }
  return path;
}

cv::Mat Decode(const Thumbnail& t) {
  // Reverse of Base64 for the test only.
  static const std::string kTable =
      "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
  std::vector<unsigned char> bytes;
  unsigned v = 0;
  int bits = 0;
  for (char c : t.jpeg_base64) {
    if (c == '=') break;
    v = (v << 6) | static_cast<unsigned>(kTable.find(c));
    bits += 6;
    if (bits >= 8) {
      bits -= 8;
      bytes.push_back(static_cast<unsigned char>((v >> bits) & 0xff));
    }
  }
  return cv::imdecode(bytes, cv::IMREAD_COLOR);
}

ThumbnailRequest Request(const std::filesystem::path& video, const std::string& stage,
                         const std::string& reason) {
  ThumbnailRequest r;
  r.clip.id = 3;
  r.clip.external_id = "c0003";
  r.clip.start_frame = 0;
  r.clip.end_frame = 39;
  r.video_path = video.string();
  r.stage = stage;
  r.reason = reason;
  return r;
}

TEST(ReportsThumbnails, Base64MatchesRfc4648Vectors) {
  auto b = [](const std::string& s) {
    return reports::Base64(std::vector<unsigned char>(s.begin(), s.end()));
  };
  EXPECT_EQ(b(""), "");
  EXPECT_EQ(b("f"), "Zg==");
  EXPECT_EQ(b("fo"), "Zm8=");
  EXPECT_EQ(b("foo"), "Zm9v");
  EXPECT_EQ(b("foob"), "Zm9vYg==");
  EXPECT_EQ(b("fooba"), "Zm9vYmE=");
  EXPECT_EQ(b("foobar"), "Zm9vYmFy");
}

TEST(ReportsThumbnails, CutShowsTheFramesEitherSide) {
  TempDir dir;
  const auto video = WriteCutVideo(dir / "cut.avi");
  auto req = Request(video, "shot_boundary", "shot_boundary");
  req.shot_summary = {{"boundaries", {20}}};
  ThumbnailOptions opt;
  opt.panel_height = 90;
  const Thumbnail t = MakeThumbnail(req, opt);
  ASSERT_TRUE(t.note.empty()) << t.note;
  const cv::Mat img = Decode(t);
  ASSERT_FALSE(img.empty());
  EXPECT_EQ(img.rows, 90);
  EXPECT_EQ(img.cols, t.width);
  // Two 4:3 panels of 120 px and a 4 px red bar between them.
  EXPECT_EQ(t.width, 2 * 120 + 4);
  const cv::Vec3b left = img.at<cv::Vec3b>(30, 60);
  const cv::Vec3b right = img.at<cv::Vec3b>(30, 124 + 60);
  EXPECT_GT(left[0], left[2] + 100) << "frame 19 is blue";
  EXPECT_GT(right[2], right[0] + 100) << "frame 20 is red";
  EXPECT_NE(t.caption.find("1 of 1 cut"), std::string::npos) << t.caption;
}

TEST(ReportsThumbnails, BorderBoxIsHighlighted) {
  TempDir dir;
  const auto video = WriteCutVideo(dir / "v.avi");
  auto req = Request(video, "out_of_frame", "out_of_frame");
  // A hand inside the frame at 5, touching the left border from frame 12.
  req.detections.push_back({.frame = 5, .kind = "hand", .x1 = 50, .y1 = 40, .x2 = 90, .y2 = 80});
  req.detections.push_back({.frame = 12, .kind = "hand", .x1 = 0, .y1 = 40, .x2 = 30, .y2 = 80,
                            .contact_state = 3, .hand_side = 1});
  ThumbnailOptions opt;
  opt.panel_height = 120;
  const Thumbnail t = MakeThumbnail(req, opt);
  ASSERT_TRUE(t.note.empty()) << t.note;
  EXPECT_NE(t.caption.find("touches the border"), std::string::npos) << t.caption;
  const cv::Mat img = Decode(t);
  ASSERT_EQ(img.cols, 160);
  // The left edge (the border the box touches) is magenta, the right is not.
  const cv::Vec3b edge = img.at<cv::Vec3b>(20, 0);
  const cv::Vec3b far = img.at<cv::Vec3b>(20, 159);
  EXPECT_GT(edge[0], 150);
  EXPECT_GT(edge[2], 150);
  EXPECT_LT(edge[1], 110);
  EXPECT_LT(far[2], 120);
}

TEST(ReportsThumbnails, MotionTracksRecoverAKnownShift) {
  const cv::Mat a = Texture(320, 240, 5);
  cv::Mat b;
  const cv::Mat shift = (cv::Mat_<double>(2, 3) << 1, 0, 4, 0, 1, -3);
  cv::warpAffine(a, b, shift, a.size(), cv::INTER_LINEAR, cv::BORDER_REFLECT);
  const auto tracks = reports::TrackMotion(a, b);
  ASSERT_GE(tracks.size(), 30u);
  std::vector<float> dx, dy;
  for (const auto& v : tracks) {
    // Points near the border see the reflected edge, not the shift.
    if (v.from.x < 20 || v.from.y < 20 || v.from.x > 300 || v.from.y > 220) continue;
    dx.push_back(v.to.x - v.from.x);
    dy.push_back(v.to.y - v.from.y);
  }
  ASSERT_GE(dx.size(), 20u);
  std::nth_element(dx.begin(), dx.begin() + dx.size() / 2, dx.end());
  std::nth_element(dy.begin(), dy.begin() + dy.size() / 2, dy.end());
  EXPECT_NEAR(dx[dx.size() / 2], 4.0, 0.2);
  EXPECT_NEAR(dy[dy.size() / 2], -3.0, 0.2);
}

TEST(ReportsThumbnails, MissingVideoGivesANoteNamingClipAndFile) {
  TempDir dir;
  const auto req = Request(dir / "gone.mp4", "camera_motion", "camera_motion");
  const Thumbnail t = MakeThumbnail(req, {});
  EXPECT_TRUE(t.jpeg_base64.empty());
  EXPECT_NE(t.note.find("c0003"), std::string::npos) << t.note;
  EXPECT_NE(t.note.find((dir / "gone.mp4").string()), std::string::npos) << t.note;
}

TEST(ReportsThumbnails, CorruptVideoGivesANote) {
  TempDir dir;
  testing::WriteFile(dir / "bad.mp4", "this is not a video");
  const Thumbnail t = MakeThumbnail(Request(dir / "bad.mp4", "activity", "no_activity"), {});
  EXPECT_TRUE(t.jpeg_base64.empty());
  EXPECT_NE(t.note.find("bad.mp4"), std::string::npos) << t.note;
  EXPECT_NE(t.note.find("c0003"), std::string::npos) << t.note;
}

TEST(ReportsThumbnails, SpanPastTheEndShowsTheLastDecodedFrame) {
  TempDir dir;
  const auto video = WriteCutVideo(dir / "v.avi");
  auto req = Request(video, "activity", "no_activity");
  req.clip.end_frame = 79;  // the file has 40 frames
  ThumbnailOptions opt;
  opt.panel_height = 90;
  const Thumbnail t = MakeThumbnail(req, opt);
  ASSERT_TRUE(t.note.empty()) << t.note;
  const cv::Mat img = Decode(t);
  ASSERT_EQ(img.cols, 3 * 120 + 2 * 4);
  // First frame blue; the last panel (wanted 79) is the file's last, red.
  EXPECT_GT(img.at<cv::Vec3b>(30, 60)[0], 150);
  EXPECT_GT(img.at<cv::Vec3b>(30, 2 * 124 + 60)[2], 150);
}

TEST(ReportsThumbnails, OverlayKindFollowsStageAndReason) {
  EXPECT_EQ(reports::OverlayKind("shot_boundary", "shot_boundary"), "cut");
  EXPECT_EQ(reports::OverlayKind("camera_motion", "camera_motion_unknown"), "motion");
  EXPECT_EQ(reports::OverlayKind("out_of_frame", "no_detections"), "border");
  EXPECT_EQ(reports::OverlayKind("activity", "no_activity"), "activity");
  EXPECT_EQ(reports::OverlayKind("interaction", "no_interaction"), "boxes");
}

}  // namespace
}  // namespace doasido
