// Depth EXR and mask PNG parts: files written here with OpenEXR's own API in
// the layouts other tools use (RGB, luminance, one oddly named channel, half
// floats, a shifted data window) read as the expected depth; masks read as
// 0/255 whatever non-zero value marks the foreground.
#include <cmath>
#include <limits>

#include <Imath/ImathBox.h>
#include <Imath/half.h>
#include <OpenEXR/ImfChannelList.h>
#include <OpenEXR/ImfFrameBuffer.h>
#include <OpenEXR/ImfHeader.h>
#include <OpenEXR/ImfOutputFile.h>
#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <opencv2/imgcodecs.hpp>

#include "core/error.h"
#include "recon/bundle/exr_io.h"
#include "recon/bundle/mask_io.h"
#include "tests/test_util.h"

namespace doasido::recon {
namespace {

using ::testing::HasSubstr;
using doasido::testing::TempDir;

constexpr int kW = 7, kH = 5;

float Value(int x, int y) { return 0.5f + 0.25f * x + 0.125f * y; }

// Writes a kW x kH float EXR whose channel `names[i]` holds Value + i, with
// the data window starting at (ox, oy).
void WriteExr(const std::filesystem::path& path, const std::vector<std::string>& names,
              Imf::PixelType type = Imf::FLOAT, int ox = 0, int oy = 0) {
  Imath::Box2i window(Imath::V2i(ox, oy), Imath::V2i(ox + kW - 1, oy + kH - 1));
  Imf::Header header(window, window);
  std::vector<std::vector<float>> planes;
  for (size_t c = 0; c < names.size(); ++c) {
    header.channels().insert(names[c], Imf::Channel(type));
    std::vector<float> plane(kW * kH);
    for (int y = 0; y < kH; ++y) {
      for (int x = 0; x < kW; ++x) plane[static_cast<size_t>(y * kW + x)] = Value(x, y) + c;
    }
    planes.push_back(plane);
  }
  // Output slices must have the file's pixel type.
  std::vector<std::vector<half>> halves;
  for (const auto& plane : planes) halves.emplace_back(plane.begin(), plane.end());
  const size_t size = type == Imf::HALF ? sizeof(half) : sizeof(float);
  Imf::OutputFile out(path.c_str(), header);
  Imf::FrameBuffer fb;
  for (size_t c = 0; c < names.size(); ++c) {
    char* data = type == Imf::HALF ? reinterpret_cast<char*>(halves[c].data())
                                   : reinterpret_cast<char*>(planes[c].data());
    // Slices are addressed in data-window coordinates.
    char* base = data - (static_cast<std::ptrdiff_t>(ox) + static_cast<std::ptrdiff_t>(oy) * kW) *
                            static_cast<std::ptrdiff_t>(size);
    fb.insert(names[c], Imf::Slice(type, base, size, size * kW));
  }
  out.setFrameBuffer(fb);
  out.writePixels(kH);
}

void ExpectDepth(const cv::Mat& z, float offset, float tolerance = 0) {
  ASSERT_EQ(z.type(), CV_32FC1);
  ASSERT_EQ(z.cols, kW);
  ASSERT_EQ(z.rows, kH);
  for (int y = 0; y < kH; ++y) {
    for (int x = 0; x < kW; ++x) EXPECT_NEAR(z.at<float>(y, x), Value(x, y) + offset, tolerance);
  }
}

TEST(ExrTest, PicksZThenYThenRThenTheOnlyChannel) {
  TempDir dir;
  WriteExr(dir / "zrgb.exr", {"R", "G", "B", "Z"});  // Z holds offset 3
  ExpectDepth(ReadDepthExr(dir / "zrgb.exr"), 3);
  WriteExr(dir / "rgb.exr", {"R", "G", "B"});
  ExpectDepth(ReadDepthExr(dir / "rgb.exr"), 0);
  WriteExr(dir / "ya.exr", {"A", "Y"});
  ExpectDepth(ReadDepthExr(dir / "ya.exr"), 1);
  WriteExr(dir / "one.exr", {"distance"});
  ExpectDepth(ReadDepthExr(dir / "one.exr"), 0);
}

TEST(ExrTest, HalfChannelsAndShiftedWindowsRead) {
  TempDir dir;
  WriteExr(dir / "half.exr", {"Z"}, Imf::HALF);
  ExpectDepth(ReadDepthExr(dir / "half.exr"), 0, 2e-3f);  // half has 11 significant bits
  WriteExr(dir / "shifted.exr", {"Z"}, Imf::FLOAT, 3, 2);
  ExpectDepth(ReadDepthExr(dir / "shifted.exr"), 0);
}

TEST(ExrTest, AmbiguousChannelsAreRejectedNamingThem) {
  TempDir dir;
  WriteExr(dir / "ab.exr", {"A", "B"});
  try {
    ReadDepthExr(dir / "ab.exr");
    ADD_FAILURE() << "no error";
  } catch (const Error& e) {
    EXPECT_EQ(e.code(), "bad_bundle");
    EXPECT_THAT(std::string(e.what()), HasSubstr("[A, B]"));
    EXPECT_THAT(e.site().file, HasSubstr("ab.exr"));
  }
  doasido::testing::WriteFile(dir / "junk.exr", "not an exr");
  EXPECT_THROW(ReadDepthExr(dir / "junk.exr"), Error);
}

TEST(ExrTest, WrittenDepthKeepsInfZeroAndExactFloats) {
  TempDir dir;
  cv::Mat z(kH, kW, CV_32F);
  for (int y = 0; y < kH; ++y) {
    for (int x = 0; x < kW; ++x) z.at<float>(y, x) = 1.0f / (3.0f + x + 7 * y);
  }
  z.at<float>(0, 0) = std::numeric_limits<float>::infinity();
  z.at<float>(1, 1) = 0.0f;
  WriteDepthExr(dir / "d.exr", z);
  const cv::Mat r = ReadDepthExr(dir / "d.exr");
  EXPECT_EQ(cv::norm(r(cv::Rect(2, 2, 3, 3)), z(cv::Rect(2, 2, 3, 3)), cv::NORM_INF), 0.0);
  EXPECT_TRUE(std::isinf(r.at<float>(0, 0)));
  EXPECT_FALSE(IsValidDepth(r.at<float>(0, 0)));
  EXPECT_FALSE(IsValidDepth(r.at<float>(1, 1)));
  EXPECT_TRUE(IsValidDepth(r.at<float>(2, 2)));
  // A sub-image (not continuous in memory) writes its own pixels.
  WriteDepthExr(dir / "roi.exr", z(cv::Rect(1, 1, 4, 3)));
  const cv::Mat roi = ReadDepthExr(dir / "roi.exr");
  ASSERT_EQ(roi.size(), cv::Size(4, 3));
  EXPECT_EQ(roi.at<float>(2, 3), z.at<float>(3, 4));
}

TEST(MaskTest, AnyNonZeroIsForeground) {
  TempDir dir;
  cv::Mat m = cv::Mat::zeros(kH, kW, CV_8U);
  m.at<std::uint8_t>(1, 2) = 1;
  m.at<std::uint8_t>(3, 4) = 7;
  m.at<std::uint8_t>(4, 6) = 255;
  cv::imwrite((dir / "m.png").string(), m);
  const cv::Mat r = ReadMaskPng(dir / "m.png");
  EXPECT_EQ(cv::countNonZero(r), 3);
  EXPECT_EQ(r.at<std::uint8_t>(1, 2), 255);
  EXPECT_EQ(r.at<std::uint8_t>(3, 4), 255);
  WriteMaskPng(dir / "w.png", m);
  EXPECT_EQ(cv::norm(cv::imread((dir / "w.png").string(), cv::IMREAD_UNCHANGED), r,
                     cv::NORM_INF),
            0.0);
}

TEST(MaskTest, SixteenBitMaskIsRejected) {
  TempDir dir;
  cv::imwrite((dir / "m16.png").string(), cv::Mat(kH, kW, CV_16U, cv::Scalar(1000)));
  try {
    ReadMaskPng(dir / "m16.png");
    ADD_FAILURE() << "no error";
  } catch (const Error& e) {
    EXPECT_THAT(std::string(e.what()), HasSubstr("16-bit"));
    EXPECT_THAT(e.site().file, HasSubstr("m16.png"));
  }
  EXPECT_THROW(ReadMaskPng(dir / "absent.png"), Error);
}

}  // namespace
}  // namespace doasido::recon
