// SHA-256 of a file (OpenSSL EVP), as 64 lower-case hex digits.
#pragma once

#include <filesystem>
#include <string>

namespace doasido::ingest {

// Throws Error("io") naming the file when it cannot be read.
std::string FileSha256(const std::filesystem::path& path);

}  // namespace doasido::ingest
