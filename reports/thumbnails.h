// Example thumbnails for the report: a few frames of a clip, scaled to a
// common height, with overlays that show why a filter decided as it did:
//   shot_boundary   the frames either side of each cut (up to two cuts)
//   camera_motion   two frames half a second apart, the second with
//                   Shi-Tomasi + pyramidal Lucas-Kanade motion vectors
//   out_of_frame    the first frame whose hand or object box touches the
//                   frame border, that box and border edge highlighted
//   activity        the first, middle and last frame of the clip
//   anything else   the middle frame
// Every panel carries the clip's hand (green, with side and contact state)
// and object (orange) boxes of that frame or the nearest annotated one.
#pragma once

#include <cstdint>
#include <optional>
#include <opencv2/core.hpp>
#include <string>
#include <vector>

#include "core/config.h"
#include "core/records.h"

namespace doasido::reports {

struct ThumbnailOptions {
  int max_per_reason = 6;  // clips per reason strip
  int panel_height = 120;  // pixels
  int jpeg_quality = 80;
  int analysis_size = 320;  // decode at this longer side (0: full size)
  // Boxes of a frame without detections come from the nearest frame with
  // some within this many frames.
  int box_search_frames = 30;
};
NLOHMANN_DEFINE_TYPE_NON_INTRUSIVE_WITH_DEFAULT(ThumbnailOptions, max_per_reason, panel_height,
                                                jpeg_quality, analysis_size, box_search_frames)
// Valid ranges (reports/report_options.cc); throws Error("bad_config").
void CheckConfig(const ThumbnailOptions& c, const std::string& section);

struct ThumbnailRequest {
  ClipRecord clip;
  std::string video_path;  // absolute path or URL
  std::vector<Detection> detections;
  std::string stage;   // the stage that decided
  std::string reason;  // its reason code
  // The shot_boundary stage's summary ("boundaries": file frame indices of
  // the first frame of each new shot); null when that stage did not run.
  Json shot_summary;
};

struct Thumbnail {
  ClipId clip = 0;
  std::string label;    // external id, or "clip <id>"
  std::string caption;  // what the panels show
  std::string jpeg_base64;  // empty when the video could not be read
  int width = 0, height = 0;
  std::string note;  // why there is no image (names the clip and file)
};

// Which overlay a (stage, reason) gets: "cut", "motion", "border",
// "activity" or "boxes".
std::string OverlayKind(const std::string& stage, const std::string& reason);

// Decodes the frames it needs and draws the overlay. Never throws for an
// unreadable video: the Thumbnail then has a note instead of an image.
Thumbnail MakeThumbnail(const ThumbnailRequest& request, const ThumbnailOptions& options);

struct MotionVector {
  cv::Point2f from, to;
};
// Shi-Tomasi corners of `a` (at most `max_corners`, quality 0.01, min
// distance 7) tracked into `b` by pyramidal Lucas-Kanade, keeping tracks
// found in both directions within 1 px (forward-backward check). Both
// images BGR or gray, same size.
std::vector<MotionVector> TrackMotion(const cv::Mat& a, const cv::Mat& b, int max_corners = 150);

// Whether a box (full-resolution pixels, x2/y2 exclusive) lies within
// `margin` pixels of the border of a `width` x `height` frame.
bool TouchesBorder(const Detection& d, int width, int height, double margin = 2.0);

// Draws boxes given in full-resolution pixels onto `image`, which is the
// frame scaled by `scale`; box `highlight` (index into `boxes`, -1: none)
// is drawn thick in magenta.
void DrawDetections(cv::Mat& image, const std::vector<Detection>& boxes, double scale,
                    int highlight = -1);

// RFC 4648 base64 of `bytes`.
std::string Base64(const std::vector<unsigned char>& bytes);

}  // namespace doasido::reports
