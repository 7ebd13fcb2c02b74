// Outputs that are whole or absent. Every writing command builds its output
// in a temporary sibling (.<name>.tmp-<pid>-<hex>, hidden, on the same
// filesystem) and puts it in place with one rename at the end, so a killed
// or failed command leaves the earlier output (or none), never part of one.
// An existing folder is replaced with one atomic exchange (renameat2
// RENAME_EXCHANGE), then the old one is removed; a file with one rename.
//
// Which existing outputs may be replaced is CheckOutputPath's business
// (core/output_path.h); these functions only write.
#pragma once

#include <filesystem>
#include <functional>
#include <optional>
#include <string>
#include <vector>

namespace doasido {

enum class OutputKind { kFile, kFolder };

// Runs `write(temp)`, flushes what it wrote to disk (fsync, every file of
// a folder) and puts `temp` in place of `out`. For a folder output `temp`
// exists (empty) when `write` is called; for a file it does not.
// Temporaries that killed commands left beside `out` (their process is
// gone) are removed first and, when `removed` is given, named there. On an
// exception the temporary is removed, `out` is untouched and the exception
// passes on; a failed rename throws Error("io") naming `out`.
void WriteWhole(const std::filesystem::path& out, OutputKind kind,
                const std::function<void(const std::filesystem::path& temp)>& write,
                std::vector<std::filesystem::path>* removed = nullptr);

// WriteWhole for a file whose bytes are known.
void WriteFileWhole(const std::filesystem::path& out, const std::string& bytes);

// A fresh name for a temporary sibling of `out` (not created).
std::filesystem::path TempSibling(const std::filesystem::path& out);
// A temporary is ours only with its marker: a file beside it,
// `<temporary>.doasido-temporary`, holding "doasido temporary" and the
// temporary's name. MarkTemporary writes it (Error("io") when it cannot)
// before the temporary is made; UnmarkTemporary removes it once the
// temporary is renamed into place or removed.
void MarkTemporary(const std::filesystem::path& temp);
void UnmarkTemporary(const std::filesystem::path& temp);
// Removes the temporaries in `folder` (of any output) that carry their
// marker and whose writing process is gone (and markers left without their
// temporary); returns the temporaries removed. A name of the same shape
// without the marker, or with a pid that cannot be one, is a person's file
// and is left alone.
std::vector<std::filesystem::path> RemoveAbandonedTemporaries(const std::filesystem::path& folder);
// The process id written as `digits` (1..pid_t's maximum); nullopt for
// anything else, never an exception.
std::optional<long> ParsePid(const std::string& digits);

// True when a process with this id runs on this machine (the temporaries'
// and the merge journal's owner test).
bool ProcessAlive(long pid);

}  // namespace doasido
