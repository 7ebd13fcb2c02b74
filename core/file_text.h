// Whole-file reads: the one place a file the project parses becomes a
// string (lists, MJCF, URDF, JSON profiles, archives).
#pragma once

#include <filesystem>
#include <optional>
#include <string>

namespace doasido {

// The bytes of `path`; std::nullopt when it cannot be opened.
std::optional<std::string> TryReadFile(const std::filesystem::path& path);

// The bytes of `path`. Throws Error(code, message) naming `label` (else the
// path) as the file when it cannot be opened.
std::string ReadFileOrThrow(const std::filesystem::path& path, const std::string& code,
                            const std::string& message, const std::string& label = {});

}  // namespace doasido
