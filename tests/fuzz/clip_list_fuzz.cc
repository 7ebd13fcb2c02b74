// Every clip-list reader (ingest/clip_list.h) on arbitrary bytes. The first
// byte picks the format; the rest is the list (for EPIC, the list and its
// video-info CSV; for VOC, up to four annotation files, split at "\n===\n").
// A reader may refuse a file or a row only with doasido::Error (or a row
// error); anything else (another exception, a crash, a leak) is a finding.
#include <cstddef>
#include <cstdint>
#include <string>

#include "core/error.h"
#include "ingest/clip_list.h"
#include "tests/fuzz/fuzz_files.h"

namespace {

using doasido::fuzz::SplitParts;
using doasido::fuzz::WriteInput;

std::filesystem::path WriteList(std::uint8_t format, std::string_view text,
                                doasido::ingest::ListOptions& options) {
  namespace fs = std::filesystem;
  switch (format % 7) {
    case 0: return WriteInput("list.csv", text);
    case 1: return WriteInput("list.tsv", text);
    case 2: return WriteInput("list.jsonl", text);
    case 3: return WriteInput("list.json", text);
    case 4: return WriteInput("frames.txt", text);
    case 5: {
      const auto parts = SplitParts(text);
      options.epic_video_info =
          WriteInput("EPIC_100_video_info.csv", parts.size() > 1 ? parts[1] : "");
      return WriteInput("epic.csv", "narration_id," + std::string(parts[0]));
    }
    default: {
      const auto dir = doasido::fuzz::ScratchDir() / "voc";
      std::error_code ec;
      fs::remove_all(dir, ec);
      const auto parts = SplitParts(text);
      for (size_t i = 0; i < parts.size() && i < 4; ++i) {
        WriteInput("voc/Annotations/kitchen_v_ab" + std::to_string(i % 2) + "_frame00000" +
                       std::to_string(i) + ".xml",
                   parts[i]);
      }
      return dir;
    }
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size < 1) return 0;
  doasido::ingest::ListOptions options;
  options.check_files = (data[0] & 0x80) != 0;
  options.video_url_template = (data[0] & 0x40) ? "https://example.org/{id}" : "";
  const std::string_view text(reinterpret_cast<const char*>(data) + 1, size - 1);
  try {
    const auto list = WriteList(data[0], text, options);
    const auto read = doasido::ingest::ReadClipList(list, options);
    for (const auto& e : read.errors) (void)e.Format();
  } catch (const doasido::Error&) {
  }
  return 0;
}
