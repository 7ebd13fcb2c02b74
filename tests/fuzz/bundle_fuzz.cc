// The clip bundle reader (recon/bundle/bundle.h) on arbitrary bytes: models write
// these folders, and a broken model must not crash the recon stage. With
// the first byte even, the rest is one .npy file (recon/bundle/npy.h ParseNpy);
// otherwise it is split at "\n===\n" into meta.json, K.npz, hands.npz,
// object/poses.npz, gravity.npz and tracks.npz of one bundle folder. Only
// doasido::Error may come out.
#include <cstddef>
#include <cstdint>
#include <string>

#include "core/error.h"
#include "recon/bundle/bundle.h"
#include "recon/bundle/npy.h"
#include "tests/fuzz/fuzz_files.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size < 1) return 0;
  const std::string_view rest(reinterpret_cast<const char*>(data) + 1, size - 1);
  try {
    if (data[0] % 2 == 0) {
      (void)doasido::recon::ParseNpy(std::string(rest), "fuzz.npy");
      return 0;
    }
    static const char* kFiles[] = {"meta.json",   "K.npz",       "hands.npz",
                                   "object/poses.npz", "gravity.npz", "tracks.npz"};
    const auto dir = doasido::fuzz::ScratchDir() / "bundle";
    std::error_code ec;
    std::filesystem::remove_all(dir, ec);
    const auto parts = doasido::fuzz::SplitParts(rest);
    for (size_t i = 0; i < parts.size() && i < std::size(kFiles); ++i) {
      doasido::fuzz::WriteInput(std::string("bundle/") + kFiles[i], parts[i]);
    }
    (void)doasido::recon::ReadBundle(dir);
  } catch (const doasido::Error&) {
  }
  return 0;
}
