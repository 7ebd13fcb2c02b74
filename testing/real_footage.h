// The labelled real footage (bench/real_footage_labels.tsv): spans of
// public videos from ../shared/data and from Debian packages that
// scripts/setup.sh installs, each labelled by hand per filter, and the one
// rule that splits them into a tuning half and a held-back half.
//
// The split (docs/benchmarks.md, "Real footage"): a clip's half follows its
// source video, so spans of one video never straddle the halves.
//   - The 12 videos of ../shared/data/videos are the tuning half: every
//     threshold and speed change before the split was set on them, so they
//     cannot be held back.
//   - Any other source: SHA-256 of the video's file name (the last part of
//     its path, without a ".gz" ending; e.g. "cup.mp4") — first byte even:
//     tuning; odd: held back.
#pragma once

#include <cstdint>
#include <filesystem>
#include <map>
#include <string>
#include <vector>

namespace doasido::testing {

// Error code of a table that does not read.
inline constexpr const char* kBadLabels = "bad_labels";
// What a filter should decide (the label cells); "-" is not scored.
inline constexpr const char* kLabelPass = "pass";
inline constexpr const char* kLabelTrimmed = "trimmed";
inline constexpr const char* kLabelReject = "reject";

enum class Half { kTuning, kHeldBack };
const char* ToString(Half half);

struct RealFootageClip {
  std::string id;
  std::string source;  // as the table writes it
  std::int64_t first_frame = 0;
  std::int64_t last_frame = -1;  // inclusive; -1: to the end of the file
  // Filter (column name) -> pass | trimmed | reject; unscored cells absent.
  std::map<std::string, std::string> labels;
  std::string origin;
  std::string what;
  Half half = Half::kTuning;
};

// The half of a clip whose source is `source` (see the file comment).
Half SplitHalf(const std::string& source);

// Reads the table. The label columns are those between `last` and `origin`.
// Throws Error(kBadLabels) naming the file, line and field for a missing
// column, a bad frame number or label, or a repeated id.
std::vector<RealFootageClip> ReadRealFootage(const std::filesystem::path& table);

// The file to decode for `source`: "shared:P" -> shared_data / P; an
// absolute path as it is; a ".gz" file decompressed once into `cache_dir`.
// Throws Error("video_unreadable") naming the file when it is not there
// (for a package's file: "run scripts/setup.sh").
std::filesystem::path ResolveRealFootage(const std::string& source,
                                         const std::filesystem::path& shared_data,
                                         const std::filesystem::path& cache_dir);

}  // namespace doasido::testing
