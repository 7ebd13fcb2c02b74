// Copying a folder tree into one of ours.
#pragma once

#include <filesystem>
#include <system_error>

namespace doasido {

// Copies the tree at `from` to `to` (created, with its missing parents),
// following symbolic links. The copies are ours whatever the source's
// modes: folders are made with this process's default modes and every file
// gets owner read and write, so a tree copied out of a read-only database
// (files 0444, folders 0555) can still be filled, replaced and removed.
// The first failure stops the copy and is left in `ec`; what was copied so
// far stays for the caller to remove.
void CopyTreeAsOurs(const std::filesystem::path& from, const std::filesystem::path& to,
                    std::error_code& ec);

}  // namespace doasido
