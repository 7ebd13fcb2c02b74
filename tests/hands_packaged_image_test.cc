// Labelled photos read where a package installed them (hands/packaged_image.h):
// a Qt resource file written here byte by byte from the format's definition
// (big-endian header "qres", tree, data, names) holding a PNG with an alpha
// channel, read back composited over white with its exact pixels; a file of
// an npm package in the npm folder; and clear reasons for what cannot be read.
#include <gtest/gtest.h>

#include <cstdlib>
#include <fstream>
#include <string>
#include <vector>

#include <opencv2/imgcodecs.hpp>

#include "hands/packaged_image.h"
#include "test_util.h"

namespace doasido::hands {
namespace {

namespace fs = std::filesystem;
using Bytes = std::vector<unsigned char>;

void Put32(Bytes* b, uint32_t v) {
  for (int s = 24; s >= 0; s -= 8) b->push_back(static_cast<unsigned char>(v >> s));
}
void Put16(Bytes* b, uint16_t v) {
  b->push_back(static_cast<unsigned char>(v >> 8));
  b->push_back(static_cast<unsigned char>(v));
}

// A version-2 resource file with /pics/hand.png = `png` (uncompressed) and
// /pics/packed.png flagged as zlib-compressed (its bytes are the same).
Bytes ResourceFile(const Bytes& png) {
  const std::vector<std::string> names = {"pics", "hand.png", "packed.png"};
  Bytes name_block;
  std::vector<uint32_t> name_at;
  for (const std::string& n : names) {
    name_at.push_back(static_cast<uint32_t>(name_block.size()));
    Put16(&name_block, static_cast<uint16_t>(n.size()));
    Put32(&name_block, 0);  // the hash: not read
    for (char c : n) Put16(&name_block, static_cast<uint16_t>(c));
  }
  Bytes data;
  Put32(&data, static_cast<uint32_t>(png.size()));
  data.insert(data.end(), png.begin(), png.end());
  // Nodes (22 bytes each in version 2): 0 root dir -> 1 "pics" dir -> 2, 3 files.
  Bytes tree;
  const auto dir = [&tree](uint32_t name, uint32_t count, uint32_t first) {
    Put32(&tree, name);
    Put16(&tree, 2);
    Put32(&tree, count);
    Put32(&tree, first);
    tree.insert(tree.end(), 8, 0);  // modification time
  };
  const auto file = [&tree](uint32_t name, uint16_t flags, uint32_t data_at) {
    Put32(&tree, name);
    Put16(&tree, flags);
    Put16(&tree, 0);  // country
    Put16(&tree, 0);  // language
    Put32(&tree, data_at);
    tree.insert(tree.end(), 8, 0);
  };
  dir(0, 1, 1);
  dir(name_at[0], 2, 2);
  file(name_at[1], 0, 0);
  file(name_at[2], 1, 0);
  Bytes out = {'q', 'r', 'e', 's'};
  const uint32_t header = 20;
  Put32(&out, 2);
  Put32(&out, header);                                      // tree
  Put32(&out, header + static_cast<uint32_t>(tree.size()));  // data
  Put32(&out, header + static_cast<uint32_t>(tree.size() + data.size()));  // names
  out.insert(out.end(), tree.begin(), tree.end());
  out.insert(out.end(), data.begin(), data.end());
  out.insert(out.end(), name_block.begin(), name_block.end());
  return out;
}

void Write(const fs::path& path, const Bytes& bytes) {
  fs::create_directories(path.parent_path());
  std::ofstream(path, std::ios::binary)
      .write(reinterpret_cast<const char*>(bytes.data()), static_cast<std::streamsize>(bytes.size()));
}

// 2x1 BGRA: an opaque blue pixel and a fully transparent one whose colour
// channels hold junk (as cut-out photos' do).
Bytes TwoPixelPng() {
  cv::Mat bgra(1, 2, CV_8UC4);
  bgra.at<cv::Vec4b>(0, 0) = {200, 10, 20, 255};
  bgra.at<cv::Vec4b>(0, 1) = {0, 0, 0, 0};
  Bytes png;
  cv::imencode(".png", bgra, png);
  return png;
}

TEST(PackagedImage, QtResourceEntryIsReadAndAlphaCompositedOverWhite) {
  testing::TempDir tmp;
  const fs::path rcc = tmp.path() / "share/app/pics.rcc";
  Write(rcc, ResourceFile(TwoPixelPng()));
  std::string why;
  const cv::Mat image = ReadPackagedImage(rcc.string() + ":/pics/hand.png", &why);
  ASSERT_FALSE(image.empty()) << why;
  ASSERT_EQ(image.type(), CV_8UC3);
  ASSERT_EQ(image.size(), cv::Size(2, 1));
  EXPECT_EQ(image.at<cv::Vec3b>(0, 0), cv::Vec3b(200, 10, 20));
  EXPECT_EQ(image.at<cv::Vec3b>(0, 1), cv::Vec3b(255, 255, 255));

  EXPECT_TRUE(ReadPackagedImage(rcc.string() + ":/pics/missing.png", &why).empty());
  EXPECT_NE(why.find("no entry /pics/missing.png"), std::string::npos) << why;
  EXPECT_TRUE(ReadPackagedImage(rcc.string() + ":/pics/packed.png", &why).empty());
  EXPECT_NE(why.find("compressed"), std::string::npos) << why;
  EXPECT_TRUE(ReadPackagedImage(rcc.string() + ":/pics", &why).empty());
  EXPECT_NE(why.find("directory"), std::string::npos) << why;
  Write(tmp.path() / "not.rcc", Bytes{'n', 'o', 'p', 'e', 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0,
                                      0, 0, 0, 0, 0});
  EXPECT_TRUE(ReadPackagedImage((tmp.path() / "not.rcc").string() + ":/a.png", &why).empty());
  EXPECT_NE(why.find("not a Qt resource file"), std::string::npos) << why;
}

TEST(PackagedImage, NpmPackageFileAndPlainFile) {
  testing::TempDir tmp;
  Write(tmp.path() / "node_modules/some-pkg/assets/hand.png", TwoPixelPng());
  const char* old = std::getenv("DOASIDO_NPM_DIR");
  const std::string kept = old ? old : "";
  setenv("DOASIDO_NPM_DIR", tmp.path().c_str(), 1);
  std::string why;
  const cv::Mat npm = ReadPackagedImage("npm:some-pkg/assets/hand.png", &why);
  const cv::Mat missing = ReadPackagedImage("npm:some-pkg/assets/none.png", &why);
  if (old) setenv("DOASIDO_NPM_DIR", kept.c_str(), 1); else unsetenv("DOASIDO_NPM_DIR");
  ASSERT_FALSE(npm.empty());
  EXPECT_EQ(npm.at<cv::Vec3b>(0, 1), cv::Vec3b(255, 255, 255));
  EXPECT_TRUE(missing.empty());
  EXPECT_NE(why.find("none.png"), std::string::npos) << why;

  const fs::path plain = tmp.path() / "gray.png";
  cv::imwrite(plain.string(), cv::Mat(3, 4, CV_8UC1, cv::Scalar(77)));
  const cv::Mat gray = ReadPackagedImage(plain.string());
  ASSERT_EQ(gray.type(), CV_8UC3);  // one channel made three, as imread's colour mode
  EXPECT_EQ(gray.at<cv::Vec3b>(2, 3), cv::Vec3b(77, 77, 77));
}

}  // namespace
}  // namespace doasido::hands
