// Export of a version as one robomimic HDF5 file (libhdf5), the layout
// robomimic's SequenceDataset reads (REFERENCE §6):
//   data                 attrs total (samples), env_args (JSON)
//   data/demo_<i>        attrs num_samples, episode_id, clip_id, hand_only (1:
//                        no object: no object obs, states are the joints alone)
//     actions (N,A)      the actuator targets (ctrl) when the trajectory has
//                        them, else the next frame's joint positions
//     states (N,S)       joint positions, then the object pose when present
//     rewards (N)        0, and 1 on the last sample (a kept demonstration)
//     dones (N)          0, and 1 on the last sample
//     obs/<key>, next_obs/<key> (N,·)  robot0_joint_pos; object (tx..qz) and
//                        hand_keypoints (63, NaN where unseen) when present
//   mask/<split>         names of the demos in each split
// demo_i is the version's episode i.
#pragma once

#include <cstdint>
#include <filesystem>

namespace doasido::dataset {

struct ExportSummary {
  std::int64_t episodes = 0;
  std::int64_t frames = 0;
  std::int64_t bytes = 0;  // size of what was written
};

// Writes `out_file` (replacing it) from the version at `version_dir`.
// Throws Error("io") naming a file it cannot read or write,
// Error("bad_trajectory") naming an episode's trajectory that does not read.
ExportSummary ExportRobomimic(const std::filesystem::path& version_dir,
                              const std::filesystem::path& out_file);

}  // namespace doasido::dataset
