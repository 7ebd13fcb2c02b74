// From per-frame hands to tracks: one track per hand, each with one side for
// its whole life (no left/right swap mid-track).
//
// The landmarker already follows a hand from frame to frame (the landmark
// model runs on a crop around the previous frame's keypoints, the palm
// detector only where a hand is missing; filters/hand_landmarker.h). What it
// does not give is identity: this links its hands across frames.
//   - A detection continues the track whose last keypoint centre is nearest,
//     if it moved less than `max_jump` hand sizes since that track was last
//     seen (greedy, nearest pair first); otherwise it starts a new track.
//   - A track unseen for more than `max_gap_frames` frames ends; a later
//     detection of that hand starts a new track. Frames missing inside a
//     track (gaps of up to `max_gap_frames`) stay in it, unobserved: the fit
//     fills them and marks them filled.
//   - A track's side is the score-weighted vote of its frames' handedness.
//     Tracks that share frames get different sides: where two such tracks
//     vote alike, the one whose vote is surer keeps its side, the other
//     takes the other side; a third track overlapping both is dropped.
//   - Tracks with fewer than `min_track_frames` observed frames are dropped.
//   - A detection left over after linking whose keypoints lie on average
//     within `duplicate_distance` hand sizes of a detection taken in the
//     same frame (or of a surer new one) is dropped: the same hand found
//     twice (measured on 02_cups, bass_guitar: 0.1-0.5 hand sizes apart;
//     two real hands overlapping in 02_cups stay 0.55-1.2 apart). The find
//     nearest the track continues it. A track within twice that distance
//     of a longer track on at least half of its frames is such a second
//     find too (single frames straddle the threshold) and is dropped.
#pragma once

#include <optional>
#include <vector>

#include "hands/hand_observation.h"
#include "hands/hands_config.h"

namespace doasido::hands {

struct Track {
  Side side = Side::kRight;
  int first_frame = 0;  // index into the frames given
  // One entry per frame from first_frame on; nullopt = a gap to fill. The
  // first and last entries are observed.
  std::vector<std::optional<HandObservation>> frames;
  // Per frame: its observation was dropped as untrusted (hands/hand_outliers.h),
  // a gap now; empty: none was.
  std::vector<bool> untrusted;
  double side_vote = 0.5;  // weighted mean probability of a right hand
  int last_frame() const { return first_frame + static_cast<int>(frames.size()) - 1; }
  int observed() const;
};

struct TrackingSummary {
  int detections = 0;      // hands at or above min_score
  int dropped_tracks = 0;  // too short, or a third hand overlapping two others
  int side_changes = 0;    // tracks whose side was set against their own vote
  int duplicates = 0;      // detections dropped as a second find of a hand
};

// Tracks sorted by first frame. `summary` may be null.
std::vector<Track> BuildTracks(const std::vector<FrameObservations>& frames,
                               const TrackerConfig& config, TrackingSummary* summary = nullptr);

}  // namespace doasido::hands
