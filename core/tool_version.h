// Which doasido wrote a file: recorded in dataset manifests and reports.
#pragma once

namespace doasido {

// The release, e.g. "0.1.0" (CMake's project version).
const char* ToolVersion();
// `git describe --always --dirty` of the checkout it was built from, or
// "unknown" outside a git checkout.
const char* SourceRevision();

}  // namespace doasido
