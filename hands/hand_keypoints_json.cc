#include "hands/hand_keypoints_json.h"

#include <cmath>
#include <fstream>

#include "core/error.h"

namespace doasido::hands {
namespace {

double Round(double v, double step) { return std::round(v / step) * step; }

Json HandEntry(const FittedTrack& t, int track_index, size_t f,
               const std::optional<HandObservation>& seen, const Camera& camera) {
  Json uv = Json::array(), confidence = Json::array(), joints = Json::array();
  for (int j = 0; j < kJoints; ++j) {
    const Vec3& x = t.joints[f][j];
    const Eigen::Vector2d p = seen ? seen->uv[j] : camera.Project(x);
    uv.push_back({Round(p.x(), 1e-2), Round(p.y(), 1e-2)});
    confidence.push_back(seen ? Round(seen->confidence[j], 1e-4) : 0.0);
    joints.push_back({Round(x.x(), 1e-5), Round(x.y(), 1e-5), Round(x.z(), 1e-5)});
  }
  return {{"side", SideName(t.side)},
          {"track", track_index},
          {"score", seen ? Round(seen->score, 1e-4) : 0.0},
          {"filled", static_cast<bool>(t.filled[f])},
          {"untrusted", static_cast<bool>(t.untrusted[f])},
          {"keypoints_2d", uv},
          {"confidence", confidence},
          {"joints_camera", joints}};
}

}  // namespace

Json KeypointsJson(const DetectedFrames& detected, const HandsResult& result) {
  const Camera camera = Camera::FromK(result.intrinsics.K, detected.width, detected.height);
  std::vector<Json> frames(detected.frames.size());
  for (size_t i = 0; i < frames.size(); ++i) frames[i] = {{"frame", i}, {"hands", Json::array()}};
  // The track's observation of a frame, when it had one with a pose.
  for (size_t k = 0; k < result.tracks.size(); ++k) {
    const FittedTrack& t = result.tracks[k];
    for (size_t f = 0; f < t.joints.size(); ++f) {
      const size_t frame = static_cast<size_t>(t.first_frame) + f;
      std::optional<HandObservation> seen;
      if (!t.filled[f]) seen = t.observations.at(f);
      frames[frame]["hands"].push_back(HandEntry(t, static_cast<int>(k), f, seen, camera));
    }
  }
  const Mat3& K = result.intrinsics.K;
  return {{"width", detected.width},
          {"height", detected.height},
          {"fps", detected.fps},
          {"first_frame", detected.first_frame},
          {"K",
           {{K(0, 0), K(0, 1), K(0, 2)}, {K(1, 0), K(1, 1), K(1, 2)}, {K(2, 0), K(2, 1), K(2, 2)}}},
          {"intrinsics_source", result.intrinsics.source},
          {"intrinsics_assumed", result.intrinsics.assumed},
          {"size_prior", result.size_prior},
          {"size_assumed", result.size_prior == "adult"},
          {"joint_order", "mediapipe21"},
          {"frames", frames}};
}

void WriteTextFile(const std::filesystem::path& path, const std::string& text) {
  const std::filesystem::path temporary = path.string() + ".tmp";
  {
    std::ofstream out(temporary, std::ios::binary | std::ios::trunc);
    out << text;
    if (!out.flush()) throw Error("io", "cannot write", {.file = temporary.string()});
  }
  std::error_code ec;
  std::filesystem::rename(temporary, path, ec);
  if (ec) throw Error("io", "cannot rename into place: " + ec.message(), {.file = path.string()});
}

}  // namespace doasido::hands
