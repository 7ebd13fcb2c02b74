// SHA-256 (OpenSSL EVP) of a stream of bytes or of a file, as 64
// lower-case hex digits.
#pragma once

#include <cstddef>
#include <filesystem>
#include <memory>
#include <string>

namespace doasido::ingest {

// Incremental digest: Update as bytes arrive, then HexDigest once.
class Sha256 {
 public:
  Sha256();  // throws Error("io") when OpenSSL cannot start a digest
  ~Sha256();
  Sha256(const Sha256&) = delete;
  Sha256& operator=(const Sha256&) = delete;
  void Update(const void* data, size_t size);
  // Adds the whole content of `path`; throws Error("io") naming it.
  void UpdateFromFile(const std::filesystem::path& path);
  std::string HexDigest();

 private:
  struct Context;
  std::unique_ptr<Context> context_;
};

// Throws Error("io") naming the file when it cannot be read.
std::string FileSha256(const std::filesystem::path& path);

}  // namespace doasido::ingest
