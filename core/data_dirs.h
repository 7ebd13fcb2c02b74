// Where doasido finds the data it ships (robot models, descriptions) at run
// time: never a path of the source checkout compiled into the binary, but a
// folder beside the executable (the build tree and an installation have the
// same layout) or one named by an environment variable.
#pragma once

#include <filesystem>
#include <string>

namespace doasido {

// The folder of the running executable (from /proc/self/exe).
std::filesystem::path ExecutableDir();

// $<env_var> when set and not empty, else <ExecutableDir()>/../share/doasido/<name>
// (bin/ and tests/ sit beside share/ in the build tree and in an installation).
// Not checked for existence.
std::filesystem::path DataDir(const std::string& name, const char* env_var);

// The npm packages scripts/setup.sh installs (three.js for the review app,
// DuckDB for Parquet, MediaPipe Hands and the TFLite runtime for the hand
// detector): $DOASIDO_NPM_DIR when set, else ~/.cache/doasido/npm.
std::filesystem::path NpmDir();

}  // namespace doasido
