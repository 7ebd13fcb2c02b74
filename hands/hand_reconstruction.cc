#include "hands/hand_reconstruction.h"

#include <algorithm>
#include <optional>

namespace doasido::hands {

HandsResult ReconstructHands(const DetectedFrames& detected, const Intrinsics& intrinsics,
                             const HandsConfig& config) {
  HandsResult out;
  out.intrinsics = intrinsics;
  out.size_prior = config.fit.size_prior;
  if (config.fit.size_prior == "adult") out.prior_hand_length_m = config.fit.hand_length_m;
  const double fps = detected.fps > 0 ? detected.fps : 30.0;
  // A still image (or a clip shorter than the minimum track) keeps what it saw.
  TrackerConfig tracker = config.tracker;
  tracker.min_track_frames =
      std::min<int>(tracker.min_track_frames, static_cast<int>(detected.frames.size()));
  for (const Track& track : BuildTracks(detected.frames, tracker, &out.tracking)) {
    FittedTrack fit = FitTrack(track, intrinsics.K, fps, config.fit);
    out.fit_seconds += fit.seconds;
    if (!fit.joints.empty()) out.tracks.push_back(std::move(fit));
  }
  return out;
}

Json Summarize(const DetectedFrames& detected, const HandsResult& result) {
  Json sides = Json::object();
  double max_jump = 0, reprojection = 0;
  int fitted_frames = 0, flipped = 0, mirrored = 0, untrusted = 0;
  for (const FittedTrack& t : result.tracks) {
    flipped += t.flipped_poses;
    mirrored += t.mirrored_poses;
    untrusted += t.untrusted_frames;
  }
  for (Side side : {Side::kLeft, Side::kRight}) {
    int valid = 0, filled = 0, tracks = 0;
    std::vector<double> palms, lengths;
    // The side's wrist per frame as hands.npz holds it: a move between two
    // tracks of one side on consecutive frames counts as a jump too.
    std::vector<std::optional<Vec3>> wrist(detected.frames.size());
    for (const FittedTrack& t : result.tracks) {
      if (t.side != side) continue;
      ++tracks;
      for (size_t f = 0; f < t.joints.size(); ++f) {
        ++valid;
        lengths.push_back(HandLength(t.link_length));
        filled += t.filled[f] ? 1 : 0;
        palms.push_back(PalmWidth(t.joints[f]));
        const size_t frame = static_cast<size_t>(t.first_frame) + f;
        if (frame < wrist.size()) wrist[frame] = t.joints[f][0];
      }
      reprojection += t.reprojection_rms_px * static_cast<double>(t.joints.size());
      fitted_frames += static_cast<int>(t.joints.size());
    }
    for (size_t f = 1; f < wrist.size(); ++f) {
      if (wrist[f] && wrist[f - 1])
        max_jump = std::max(max_jump, (*wrist[f] - *wrist[f - 1]).norm());
    }
    Json s = {{"frames", valid}, {"filled_frames", filled}, {"tracks", tracks}};
    if (!palms.empty()) {
      std::nth_element(palms.begin(), palms.begin() + palms.size() / 2, palms.end());
      s["palm_width_m"] = palms[palms.size() / 2];
      std::nth_element(lengths.begin(), lengths.begin() + lengths.size() / 2, lengths.end());
      s["hand_length_m"] = lengths[lengths.size() / 2];
    }
    sides[SideName(side)] = s;
  }
  return {{"frames", detected.frames.size()},
          {"detections", result.tracking.detections},
          {"dropped_tracks", result.tracking.dropped_tracks},
          {"duplicates", result.tracking.duplicates},
          {"side_changes", result.tracking.side_changes},
          {"sides", sides},
          {"flipped_poses", flipped},
          {"mirrored_poses", mirrored},
          {"untrusted_frames", untrusted},
          {"max_root_jump_m", max_jump},
          {"reprojection_rms_px", fitted_frames ? reprojection / fitted_frames : 0.0},
          {"intrinsics_source", result.intrinsics.source},
          {"intrinsics_assumed", result.intrinsics.assumed},
          {"size_prior", result.size_prior},
          {"detect_seconds", detected.seconds},
          {"model_seconds", detected.model_seconds},
          {"fit_seconds", result.fit_seconds}};
}

}  // namespace doasido::hands
