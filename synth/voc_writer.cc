#include "synth/voc_writer.h"

#include <cmath>
#include <cstdio>
#include <fstream>
#include <opencv2/imgproc.hpp>
#include <sstream>

#include "core/error.h"

namespace doasido::synth {
namespace {

void Box(std::ostringstream& o, const char* prefix, const PixelBox& b) {
  o << "<" << prefix << "xmin>" << b.x0 + 1 << "</" << prefix << "xmin>"
    << "<" << prefix << "ymin>" << b.y0 + 1 << "</" << prefix << "ymin>"
    << "<" << prefix << "xmax>" << b.x1 + 1 << "</" << prefix << "xmax>"
    << "<" << prefix << "ymax>" << b.y1 + 1 << "</" << prefix << "ymax>";
}

std::string Fixed(double v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.6f", v);
  return buf;
}

}  // namespace

PixelBox MaskBox(const cv::Mat& mask) {
  PixelBox b;
  if (cv::countNonZero(mask) == 0) return b;
  const cv::Rect r = cv::boundingRect(mask);
  return {r.x, r.y, r.x + r.width - 1, r.y + r.height - 1};
}

std::string VocStem(const std::string& genre, const std::string& video_id, int frame) {
  char digits[16];
  std::snprintf(digits, sizeof digits, "%06d", frame);
  return genre + "_v_" + video_id + "_frame" + digits;
}

std::string VocXml(const VocFrame& f) {
  std::ostringstream o;
  const std::string stem = VocStem(f.genre, f.video_id, f.frame);
  o << "<annotation>\n"
    << "  <folder>" << f.genre << "</folder>\n"
    << "  <filename>" << stem << ".jpg</filename>\n"
    << "  <size><width>" << f.width << "</width><height>" << f.height
    << "</height><depth>3</depth></size>\n";
  for (const VocHand& h : f.hands) {
    o << "  <object>\n    <name>hand</name>\n    <pose>Unspecified</pose>\n"
      << "    <truncated>0</truncated>\n    <difficult>0</difficult>\n    <bndbox>";
    Box(o, "", h.box);
    o << "</bndbox>\n    <contactstate>" << h.contact_state << "</contactstate>\n"
      << "    <handside>" << h.side << "</handside>\n    ";
    if (h.object_box && !h.object_box->empty()) {
      Box(o, "obj", *h.object_box);
      const double dx = h.object_box->cx() - h.box.cx(), dy = h.object_box->cy() - h.box.cy();
      const double mag = std::hypot(dx, dy);
      o << "\n    <unitdx>" << Fixed(mag > 0 ? dx / mag : 0.0) << "</unitdx>"
        << "<unitdy>" << Fixed(mag > 0 ? dy / mag : 0.0) << "</unitdy>"
        << "<magnitude>" << Fixed(mag) << "</magnitude>\n";
    } else {
      o << "<objxmin>None</objxmin><objymin>None</objymin><objxmax>None</objxmax>"
           "<objymax>None</objymax>\n    <unitdx>None</unitdx><unitdy>None</unitdy>"
           "<magnitude>None</magnitude>\n";
    }
    o << "  </object>\n";
  }
  for (const VocObject& b : f.objects) {
    o << "  <object>\n    <name>targetobject</name>\n    <pose>Unspecified</pose>\n"
      << "    <truncated>0</truncated>\n    <difficult>0</difficult>\n    <bndbox>";
    Box(o, "", b.box);
    o << "</bndbox>\n    <contactleft>" << int(b.contact_left) << "</contactleft>"
      << "<contactright>" << int(b.contact_right) << "</contactright>\n  </object>\n";
  }
  o << "</annotation>\n";
  return o.str();
}

void WriteVoc(const VocFrame& frame, const std::filesystem::path& dir) {
  const auto path = dir / (VocStem(frame.genre, frame.video_id, frame.frame) + ".xml");
  std::ofstream out(path, std::ios::binary);
  out << VocXml(frame);
  if (!out) throw Error("io", "cannot write annotation", {.file = path.string()});
}

}  // namespace doasido::synth
