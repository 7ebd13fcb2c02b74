#include "hands/hand_bundle_writer.h"

#include <limits>

#include "core/file_text.h"
#include "hands/hand_keypoints_json.h"

namespace doasido::hands {
namespace {

recon::HandTrack SideTrack(const HandsResult& result, Side side, int frames) {
  recon::HandTrack out;
  out.valid.assign(static_cast<size_t>(frames), false);
  out.joints.assign(static_cast<size_t>(frames),
                    recon::Joints21::Constant(std::numeric_limits<double>::quiet_NaN()));
  for (const FittedTrack& t : result.tracks) {
    if (t.side != side) continue;
    for (size_t f = 0; f < t.joints.size(); ++f) {
      const size_t frame = static_cast<size_t>(t.first_frame) + f;
      out.valid[frame] = true;
      for (int j = 0; j < kJoints; ++j) out.joints[frame].row(j) = t.joints[f][j].transpose();
    }
  }
  return out;
}

}  // namespace

recon::ClipBundle HandBundle(const DetectedFrames& detected, const HandsResult& result) {
  recon::ClipBundle b;
  b.width = detected.width;
  b.height = detected.height;
  b.frames = static_cast<int>(detected.frames.size());
  b.fps = detected.fps > 0 ? detected.fps : 30.0;
  b.producers = {
      {"hands",
       "MediaPipe Hands (palm_detection_full + hand_landmark_full), doasido hands tracker"},
      {"hand_fit",
       result.size_prior == "adult"
           ? "doasido hand_skeleton_fit: PnP per frame, one Ceres skeleton fit per track, "
             "adult template hand (HOT3D P0003) under a hand-length prior"
           : "doasido hand_skeleton_fit: PnP per frame, one Ceres skeleton fit per track, "
             "the landmark model's bone lengths"},
      {"K", result.intrinsics.source}};
  b.K = {result.intrinsics.K};
  b.hand_left = SideTrack(result, Side::kLeft, b.frames);
  b.hand_right = SideTrack(result, Side::kRight, b.frames);
  return b;
}

void WriteHandBundle(const DetectedFrames& detected, const HandsResult& result,
                     const std::filesystem::path& dir) {
  recon::WriteBundle(HandBundle(detected, result), dir);
  // meta.json gains the one key recon's writer does not know.
  const auto meta_path = dir / "meta.json";
  Json meta = Json::parse(ReadFileOrThrow(meta_path, "io", "cannot read meta.json"));
  meta[kIntrinsicsAssumedKey] = result.intrinsics.assumed;
  // The hand's metric size is a prior, not a measurement: recorded as assumed.
  Json size = {{"prior", result.size_prior}, {"assumed", result.size_prior == "adult"}};
  if (result.size_prior == "adult") size["hand_length_m"] = result.prior_hand_length_m;
  Json fitted = Json::array();
  for (const FittedTrack& t : result.tracks) {
    fitted.push_back({{"side", SideName(t.side)},
                      {"first_frame", t.first_frame},
                      {"hand_length_m", HandLength(t.link_length)},
                      {"palm_width_m", t.link_length.back()},
                      {"model_hand_length_m", t.model_hand_length_m}});
  }
  size["tracks"] = fitted;
  meta[kHandSizeKey] = size;
  WriteTextFile(meta_path, meta.dump(2) + "\n");
  WriteTextFile(dir / kKeypointsFile, KeypointsJson(detected, result).dump() + "\n");
}

}  // namespace doasido::hands
