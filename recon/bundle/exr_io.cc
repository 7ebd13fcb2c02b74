#include "recon/bundle/exr_io.h"

#include <exception>
#include <string>

#include <Imath/ImathBox.h>
#include <OpenEXR/ImfChannelList.h>
#include <OpenEXR/ImfFrameBuffer.h>
#include <OpenEXR/ImfHeader.h>
#include <OpenEXR/ImfInputFile.h>
#include <OpenEXR/ImfOutputFile.h>

#include "core/error.h"

namespace doasido::recon {

void WriteDepthExr(const std::filesystem::path& path, const cv::Mat& depth) {
  const std::string file = path.string();
  if (depth.type() != CV_32FC1 || depth.empty()) {
    throw Error("bad_array", "depth must be a non-empty CV_32FC1 image", {.file = file});
  }
  // The frame buffer slices point into a continuous copy so that any ROI works.
  const cv::Mat z = depth.isContinuous() ? depth : depth.clone();
  try {
    Imf::Header header(z.cols, z.rows);
    header.channels().insert("Z", Imf::Channel(Imf::FLOAT));
    header.compression() = Imf::ZIP_COMPRESSION;
    Imf::OutputFile out(file.c_str(), header);
    Imf::FrameBuffer fb;
    fb.insert("Z", Imf::Slice(Imf::FLOAT, const_cast<char*>(reinterpret_cast<const char*>(z.data)),
                              sizeof(float), sizeof(float) * static_cast<size_t>(z.cols)));
    out.setFrameBuffer(fb);
    out.writePixels(z.rows);
  } catch (const std::exception& e) {
    throw Error("io", std::string("cannot write EXR: ") + e.what(), {.file = file});
  }
}

cv::Mat ReadDepthExr(const std::filesystem::path& path) {
  const std::string file = path.string();
  if (!std::filesystem::exists(path)) throw Error("io", "file does not exist", {.file = file});
  try {
    Imf::InputFile in(file.c_str());
    const Imf::ChannelList& channels = in.header().channels();
    std::string name;
    for (const char* candidate : {"Z", "Y", "R"}) {
      if (channels.findChannel(candidate) != nullptr) {
        name = candidate;
        break;
      }
    }
    int count = 0;
    std::string all;
    for (auto it = channels.begin(); it != channels.end(); ++it, ++count) {
      all += (count > 0 ? ", " : "") + std::string(it.name());
      if (name.empty() && count == 0) name = it.name();
    }
    if (name.empty() || (count > 1 && name != "Z" && name != "Y" && name != "R")) {
      throw Error("bad_bundle",
                  "no depth channel (Z, Y, R or a single channel) among [" + all + "]",
                  {.file = file, .field = "channels"});
    }
    const Imath::Box2i dw = in.header().dataWindow();
    const int width = dw.max.x - dw.min.x + 1;
    const int height = dw.max.y - dw.min.y + 1;
    cv::Mat z(height, width, CV_32FC1);
    // OpenEXR addresses slices in data-window coordinates; shift the base so
    // pixel (min.x, min.y) lands at z(0, 0).
    char* base = reinterpret_cast<char*>(z.ptr<float>()) -
                 (static_cast<std::ptrdiff_t>(dw.min.x) * sizeof(float)) -
                 (static_cast<std::ptrdiff_t>(dw.min.y) * sizeof(float) * width);
    Imf::FrameBuffer fb;
    fb.insert(name, Imf::Slice(Imf::FLOAT, base, sizeof(float), sizeof(float) * width));
    in.setFrameBuffer(fb);
    in.readPixels(dw.min.y, dw.max.y);
    return z;
  } catch (const Error&) {
    throw;
  } catch (const std::exception& e) {
    throw Error("io", std::string("cannot read EXR: ") + e.what(), {.file = file});
  }
}

void WritePointsExr(const std::filesystem::path& path, const cv::Mat& points) {
  const std::string file = path.string();
  if (points.type() != CV_32FC3 || points.empty()) {
    throw Error("bad_array", "point map must be a non-empty CV_32FC3 image", {.file = file});
  }
  const cv::Mat p = points.isContinuous() ? points : points.clone();
  try {
    Imf::Header header(p.cols, p.rows);
    header.compression() = Imf::ZIP_COMPRESSION;
    const char* names[3] = {"X", "Y", "Z"};
    for (const char* name : names) header.channels().insert(name, Imf::Channel(Imf::FLOAT));
    Imf::OutputFile out(file.c_str(), header);
    Imf::FrameBuffer fb;
    char* base = const_cast<char*>(reinterpret_cast<const char*>(p.data));
    for (int c = 0; c < 3; ++c) {
      fb.insert(names[c], Imf::Slice(Imf::FLOAT, base + c * sizeof(float), 3 * sizeof(float),
                                     3 * sizeof(float) * static_cast<size_t>(p.cols)));
    }
    out.setFrameBuffer(fb);
    out.writePixels(p.rows);
  } catch (const std::exception& e) {
    throw Error("io", std::string("cannot write EXR: ") + e.what(), {.file = file});
  }
}

cv::Mat ReadPointsExr(const std::filesystem::path& path) {
  const std::string file = path.string();
  if (!std::filesystem::exists(path)) throw Error("io", "file does not exist", {.file = file});
  try {
    Imf::InputFile in(file.c_str());
    const char* names[3] = {"X", "Y", "Z"};
    for (const char* name : names) {
      if (in.header().channels().findChannel(name) == nullptr) {
        throw Error("bad_bundle", std::string("point map lacks channel ") + name,
                    {.file = file, .field = "channels"});
      }
    }
    const Imath::Box2i dw = in.header().dataWindow();
    const int width = dw.max.x - dw.min.x + 1;
    const int height = dw.max.y - dw.min.y + 1;
    cv::Mat p(height, width, CV_32FC3);
    char* base = reinterpret_cast<char*>(p.data) -
                 (static_cast<std::ptrdiff_t>(dw.min.x) +
                  static_cast<std::ptrdiff_t>(dw.min.y) * width) *
                     static_cast<std::ptrdiff_t>(3 * sizeof(float));
    Imf::FrameBuffer fb;
    for (int c = 0; c < 3; ++c) {
      fb.insert(names[c], Imf::Slice(Imf::FLOAT, base + c * sizeof(float), 3 * sizeof(float),
                                     3 * sizeof(float) * static_cast<size_t>(width)));
    }
    in.setFrameBuffer(fb);
    in.readPixels(dw.min.y, dw.max.y);
    return p;
  } catch (const Error&) {
    throw;
  } catch (const std::exception& e) {
    throw Error("io", std::string("cannot read EXR: ") + e.what(), {.file = file});
  }
}

}  // namespace doasido::recon
