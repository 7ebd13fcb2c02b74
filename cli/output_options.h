// The output side of writing commands: `--force` and how each command
// recognises its own earlier output (core/output_path.h refuses the rest).
#pragma once

#include <CLI/CLI.hpp>
#include <filesystem>
#include <functional>
#include <string>
#include <vector>

#include "core/output_path.h"
#include "core/whole_output.h"

namespace doasido::cli {

// Adds --force: replace an earlier output of this command at the output path.
void AddForceFlag(CLI::App& cmd, bool& force);

// A folder holding at least one of `names` (files or folders).
std::function<bool(const std::filesystem::path&)> FolderHolds(std::vector<std::string> names);
// A folder holding a hand description (a .json with "model" and "points",
// as `hand import` and `hand mirror` write; with --mjcf it is the only file).
bool HoldsHandModel(const std::filesystem::path& folder);
// A JSON file whose "format" member is `format`.
std::function<bool(const std::filesystem::path&)> JsonOfFormat(std::string format);

}  // namespace doasido::cli
