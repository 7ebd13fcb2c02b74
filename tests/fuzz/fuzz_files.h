// What the fuzz targets share: a private scratch folder per process, and
// writing the input there under a given name (parsers of lists, configs
// and bundles read files, not buffers).
#pragma once

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <string>
#include <string_view>
#include <vector>

namespace doasido::fuzz {

// A folder of this process (removed at exit); targets overwrite their files
// on every input.
const std::filesystem::path& ScratchDir();

// Writes `bytes` to ScratchDir()/name and returns the path.
std::filesystem::path WriteInput(const std::string& name, std::string_view bytes);

// Splits `bytes` at every "\n===\n" (how one input carries several files).
std::vector<std::string_view> SplitParts(std::string_view bytes);

}  // namespace doasido::fuzz
