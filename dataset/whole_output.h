// Exports that are whole or absent: an export is written into a temporary
// sibling of its output (.<name>.tmp-<pid>-<random>) and renamed into place
// at the end, so a killed export leaves the previous output (or none) and
// never a part of one. A folder replaces an existing export with one atomic
// exchange (renameat2 RENAME_EXCHANGE); a file with one rename.
#pragma once

#include <filesystem>
#include <functional>
#include <string>
#include <vector>

namespace doasido::dataset {

// Runs `write(temp)` and renames `temp` into place as `out`. `folder`: the
// export is a folder; an existing `out` is replaced only when it is an
// empty folder or holds `marker` (a file every complete export has, e.g.
// meta/doasido_manifest.json), else Error("output_exists") says why. A file
// output replaces an existing file. Temporaries that killed exports of the
// same `out` left behind (their process is gone) are removed first and
// named in `removed`. On an exception the temporary is removed and the
// exception passes on; `out` is untouched.
void WriteWhole(const std::filesystem::path& out, bool folder, const std::string& marker,
                const std::function<void(const std::filesystem::path& temp)>& write,
                std::vector<std::filesystem::path>* removed = nullptr);

}  // namespace doasido::dataset
