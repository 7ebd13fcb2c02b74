// The hand importer (retarget/urdf_import.h, retarget/embodiment.h) on
// arbitrary bytes: people bring their own robot hands as URDF or MJCF files
// and write hand descriptions by hand. The first byte picks what the rest
// is: 0 a URDF (ImportUrdf, then BuildHandModel of the description it
// writes), 1 an MJCF hand (DescribeMjcf), 2 a hand description JSON
// (LoadEmbodiment, then BuildHandModel). Every input is a file in a folder
// that also holds the two-finger test hand's meshes (meshes/*.obj, *.ply)
// and doasido's Sharpa hand model, so that inputs can name real files. Only
// doasido::Error may come out.
//
// With DOASIDO_FUZZ_SEEDS=DIR set, the target first writes its seeds there:
// the two-finger URDF of the import tests (made by C++, tests/two_finger_hand.h).
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <fstream>
#include <string>

#include "core/error.h"
#include "robot/embodiment.h"
#include "robot/urdf_import.h"
#include "tests/fuzz/fuzz_files.h"
#include "tests/two_finger_hand.h"

namespace doasido::testing {

// tests/two_finger_hand.h writes through this; the suite's version lives in
// tests/test_util.cc with GoogleTest, which the fuzz build does not link.
void WriteFile(const std::filesystem::path& path, const std::string& text) {
  if (path.has_parent_path()) std::filesystem::create_directories(path.parent_path());
  std::ofstream(path, std::ios::binary) << text;
}

}  // namespace doasido::testing

namespace {

namespace fs = std::filesystem;

const fs::path& HandDir() {
  static const fs::path dir = [] {
    const fs::path d = doasido::fuzz::ScratchDir() / "hand";
    doasido::testing::WriteTwoFingerHand(d);
    const fs::path models = doasido::retarget::BuiltinModelsDir();
    fs::copy_file(models / "sharpa_right.xml", d / "sharpa_right.xml",
                  fs::copy_options::overwrite_existing);
    return d;
  }();
  return dir;
}

void WriteSeed(const fs::path& dir, const std::string& name, char kind, const fs::path& from) {
  std::ifstream in(from, std::ios::binary);
  const std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  std::ofstream(dir / name, std::ios::binary) << kind << text;
}

}  // namespace

extern "C" int LLVMFuzzerInitialize(int*, char***) {
  if (const char* seeds = std::getenv("DOASIDO_FUZZ_SEEDS")) {
    fs::create_directories(seeds);
    WriteSeed(seeds, "two_finger.urdf", 0, HandDir() / "two_finger.urdf");
    WriteSeed(seeds, "sharpa_right.xml", 1, HandDir() / "sharpa_right.xml");
    WriteSeed(seeds, "sharpa_right.json", 2,
              doasido::retarget::BuiltinModelsDir() / "sharpa_right.json");
  }
  return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size < 1 || data[0] > 2) return 0;
  const std::string_view rest(reinterpret_cast<const char*>(data) + 1, size - 1);
  static const char* kNames[] = {"fuzz.urdf", "fuzz.xml", "fuzz.json"};
  const fs::path input = HandDir() / kNames[data[0]];
  std::ofstream(input, std::ios::binary | std::ios::trunc)
      .write(rest.data(), static_cast<std::streamsize>(rest.size()));
  const fs::path out = doasido::fuzz::ScratchDir() / "out";
  std::error_code ec;
  fs::remove_all(out, ec);
  namespace rt = doasido::retarget;
  try {
    switch (data[0]) {
      case 0: {
        const rt::ImportedHand hand = rt::ImportUrdf(input, out);
        (void)rt::BuildHandModel(rt::LoadEmbodiment(hand.description));
        break;
      }
      case 1: (void)rt::DescribeMjcf(input, out); break;
      case 2: (void)rt::BuildHandModel(rt::LoadEmbodiment(input)); break;
    }
  } catch (const doasido::Error&) {
  }
  return 0;
}
