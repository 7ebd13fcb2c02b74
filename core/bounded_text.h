// Text the database stores (errors, event details, logs) is bounded in
// bytes: a model command that prints one 9 MB line must not put 9 MB into
// every attempt's row. The tail is kept because the last lines of a failing
// program say why it failed; the whole text goes to a file the caller
// names in the kept part.
#pragma once

#include <cstddef>
#include <string>
#include <string_view>

namespace doasido {

// Bytes of an error or event detail kept in the database.
inline constexpr std::size_t kMaxStoredTextBytes = 8192;
// Bytes of one run's measurements JSON kept in the database; a stage whose
// measurements are larger fails with kMeasurementsTooLarge.
inline constexpr std::size_t kMaxMeasurementBytes = 16u << 20;
inline constexpr const char* kMeasurementsTooLarge = "measurements_too_large";
// Files in the run's artifact folder that hold what did not fit.
inline constexpr const char* kErrorLogFile = "error.log";
inline constexpr const char* kMeasurementsTooLargeFile = "measurements.json";

// `text` when it fits in `max_bytes`, else a marker saying how many bytes
// were cut (and, when `full_text_at` is not empty, where the whole text is)
// followed by the last bytes of `text`, in `max_bytes` at most. The cut
// never splits a UTF-8 sequence.
std::string BoundedTail(std::string_view text, std::size_t max_bytes = kMaxStoredTextBytes,
                        const std::string& full_text_at = {});

}  // namespace doasido
