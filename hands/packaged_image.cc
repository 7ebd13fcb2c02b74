#include "hands/packaged_image.h"

#include <cstdint>
#include <fstream>
#include <iterator>
#include <optional>
#include <sstream>
#include <vector>

#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "core/data_dirs.h"

namespace doasido::hands {
namespace {

constexpr const char* kNpmPrefix = "npm:";
constexpr const char* kRccSuffix = ".rcc:";

// A Qt resource file (rcc's binary format, versions 1-3): a header
// "qres", version, then the offsets of the tree, the data and the names,
// all big-endian. A tree node is name offset (4), flags (2), then for a
// directory its child count (4) and first child (4), for a file country and
// language (2+2) and its data offset (4); from version 2 a modification
// time (8) follows. A name is its length (2), a hash (4) and UTF-16 code
// units; a file's data is its size (4) and the bytes.
class ResourceFile {
 public:
  explicit ResourceFile(std::vector<unsigned char> bytes) : b_(std::move(bytes)) {}

  // The bytes of the entry at `path` ("/a/b.webp"); nullopt with *why.
  std::optional<std::vector<unsigned char>> Entry(const std::string& path, std::string* why) const {
    if (b_.size() < 20 || std::string(b_.begin(), b_.begin() + 4) != "qres") {
      *why = "not a Qt resource file";
      return std::nullopt;
    }
    const uint32_t version = U32(4);
    tree_ = U32(8), data_ = U32(12), names_ = U32(16);
    node_size_ = version >= 2 ? 22 : 14;
    uint32_t node = 0;  // the root directory
    std::stringstream parts(path);
    for (std::string part; std::getline(parts, part, '/');) {
      if (part.empty()) continue;
      const auto child = Child(node, part);
      if (!child) {
        *why = "no entry " + path;
        return std::nullopt;
      }
      node = *child;
    }
    const uint64_t at = tree_ + uint64_t{node} * node_size_;
    const uint16_t flags = U16(at + 4);
    if (flags & 2) {
      *why = path + " is a directory";
      return std::nullopt;
    }
    if (flags & 5) {  // zlib or zstd: GCompris stores its pictures uncompressed
      *why = path + " is stored compressed (not read here)";
      return std::nullopt;
    }
    const uint64_t d = data_ + uint64_t{U32(at + 10)};
    const uint32_t size = U32(d);
    if (d + 4 + size > b_.size()) {
      *why = path + " runs past the end of the file";
      return std::nullopt;
    }
    return std::vector<unsigned char>(b_.begin() + d + 4, b_.begin() + d + 4 + size);
  }

 private:
  uint32_t U32(uint64_t at) const {
    if (at + 4 > b_.size()) return 0;
    return uint32_t{b_[at]} << 24 | uint32_t{b_[at + 1]} << 16 | uint32_t{b_[at + 2]} << 8 |
           b_[at + 3];
  }
  uint16_t U16(uint64_t at) const {
    return at + 2 > b_.size() ? 0 : static_cast<uint16_t>(b_[at] << 8 | b_[at + 1]);
  }
  std::string Name(uint32_t offset) const {  // ASCII names only (GCompris's are)
    const uint64_t at = names_ + uint64_t{offset};
    std::string name;
    for (uint16_t i = 0, n = U16(at); i < n; ++i) name += static_cast<char>(U16(at + 6 + 2 * i));
    return name;
  }
  std::optional<uint32_t> Child(uint32_t dir, const std::string& name) const {
    const uint64_t at = tree_ + uint64_t{dir} * node_size_;
    if (!(U16(at + 4) & 2)) return std::nullopt;
    const uint32_t count = U32(at + 6), first = U32(at + 10);
    for (uint32_t c = first; c < first + count && c < b_.size() / node_size_; ++c) {
      if (Name(U32(tree_ + uint64_t{c} * node_size_)) == name) return c;
    }
    return std::nullopt;
  }

  std::vector<unsigned char> b_;
  mutable uint64_t tree_ = 0, data_ = 0, names_ = 0, node_size_ = 14;
};

std::optional<std::vector<unsigned char>> ReadFile(const std::string& path, std::string* why) {
  std::ifstream in(path, std::ios::binary);
  if (!in) {
    *why = "cannot open " + path;
    return std::nullopt;
  }
  return std::vector<unsigned char>(std::istreambuf_iterator<char>(in), {});
}

cv::Mat OverWhite(const cv::Mat& image) {
  if (image.channels() != 4) return image;
  cv::Mat bgr(image.size(), CV_8UC3);
  image.forEach<cv::Vec4b>([&bgr](const cv::Vec4b& p, const int* at) {
    const int a = p[3];
    cv::Vec3b& out = bgr.at<cv::Vec3b>(at[0], at[1]);
    for (int c = 0; c < 3; ++c) out[c] = static_cast<uchar>((p[c] * a + 255 * (255 - a) + 127) / 255);
  });
  return bgr;
}

}  // namespace

cv::Mat ReadPackagedImage(const std::string& where, std::string* why) {
  std::string reason;
  std::optional<std::vector<unsigned char>> bytes;
  const auto rcc = where.find(kRccSuffix);
  if (where.rfind(kNpmPrefix, 0) == 0) {
    bytes = ReadFile((NpmDir() / "node_modules" / where.substr(4)).string(), &reason);
  } else if (rcc != std::string::npos) {
    const std::string file = where.substr(0, rcc + 4);
    if (auto all = ReadFile(file, &reason)) {
      bytes = ResourceFile(std::move(*all)).Entry(where.substr(rcc + 5), &reason);
      if (!bytes) reason = file + ": " + reason;
    }
  } else {
    bytes = ReadFile(where, &reason);
  }
  cv::Mat image;
  if (bytes) image = cv::imdecode(*bytes, cv::IMREAD_UNCHANGED);
  if (bytes && image.empty()) reason = where + ": not an image OpenCV decodes";
  if (image.empty()) {
    if (why) *why = reason;
    return {};
  }
  if (image.depth() != CV_8U) image.convertTo(image, CV_8U, 1.0 / 257);
  if (image.channels() == 1) cv::cvtColor(image, image, cv::COLOR_GRAY2BGR);
  return OverWhite(image);
}

}  // namespace doasido::hands
