// The second half of a merge: staged stage folders moved into place after
// the rows are committed (db/database.h, MergePlacement).
#include <cstdio>
#include <regex>

#include <spdlog/spdlog.h>

#include "core/config.h"
#include "core/error.h"
#include "core/test_pause.h"
#include "core/whole_output.h"
#include "db/database.h"
#include "db/statement.h"

namespace doasido {
namespace {

namespace fs = std::filesystem;

void Rename(const fs::path& from, const fs::path& to) {
  std::error_code ec;
  fs::rename(from, to, ec);
  if (ec) throw Error("io", "cannot move a merged folder into place: " + ec.message(), {.file = to.string()});
}

// staging/<clip>/<stage> becomes <clip>/<stage>; the folder it replaces
// waits at staging/<clip>/<stage>.old until the move is done. Each step
// can be repeated after a kill.
void Place(const fs::path& staging, const fs::path& root, ClipId clip, const std::string& stage) {
  const fs::path from = staging / std::to_string(clip) / stage;
  const fs::path to = root / std::to_string(clip) / stage;
  const fs::path old = staging / std::to_string(clip) / (stage + ".old");
  std::error_code ec;
  if (fs::exists(from, ec)) {
    if (fs::exists(to, ec)) {
      if (fs::exists(old, ec)) {
        fs::remove_all(to, ec);
      } else {
        Rename(to, old);
      }
    }
    fs::create_directories(to.parent_path(), ec);
    Rename(from, to);
  }
  fs::remove_all(old, ec);
}

void Remove(const fs::path& staging, const fs::path& root, ClipId clip, const std::string& stage) {
  const fs::path gone = staging / std::to_string(clip) / (stage + ".gone");
  const fs::path folder = root / std::to_string(clip) / stage;
  std::error_code ec;
  if (fs::exists(folder, ec)) {
    fs::create_directories(gone.parent_path(), ec);
    Rename(folder, gone);  // gone from readers at once, deleted after
  }
  fs::remove_all(gone, ec);
}

}  // namespace

std::vector<fs::path> Database::RemoveAbandonedStaging() {
  static const std::regex name(R"(\.merge-([0-9]+)-[0-9a-f]+)");
  const std::optional<std::string> journal = GetMeta(kPlacementKey);
  std::vector<fs::path> removed;
  std::error_code ec;
  for (fs::directory_iterator it(artifact_root_, ec), end; !ec && it != end; it.increment(ec)) {
    const std::string leaf = it->path().filename().string();
    std::smatch m;
    if (!std::regex_match(leaf, m, name)) continue;
    const std::optional<long> pid = ParsePid(m[1].str());
    if (!pid || ProcessAlive(*pid)) continue;  // not a staging name of ours, or still merging
    if (journal && journal->find("\"" + leaf + "\"") != std::string::npos) continue;
    std::error_code rm;
    fs::remove_all(it->path(), rm);
    if (!rm) removed.push_back(it->path());
  }
  return removed;
}

std::string Database::PlacementJson(const MergePlacement& p) {
  Json j = {{"staging", p.staging}, {"pid", p.pid}, {"place", Json::array()}, {"remove", Json::array()}};
  for (const auto& [clip, stage] : p.place) j["place"].push_back({clip, stage});
  for (const auto& [clip, stage] : p.remove) j["remove"].push_back({clip, stage});
  return j.dump();
}

std::int64_t Database::FinishPlacement(bool own) {
  const std::optional<std::string> text = GetMeta(kPlacementKey);
  const Json j = text ? Json::parse(*text, nullptr, false) : Json();
  if (text && (j.is_discarded() || !j.contains("staging") || !j.contains("pid"))) {
    throw Error("database", "the merge journal in meta is not readable: " + *text,
                {.file = path_.string(), .field = kPlacementKey});
  }
  if (!text || artifact_root_.empty()) return 0;
  if (!own && ProcessAlive(j["pid"].get<long>())) return 0;  // its merge finishes it
  const fs::path staging = artifact_root_ / j["staging"].get<std::string>();
  std::int64_t n = 0;
  for (const Json& p : j.value("place", Json::array())) {
    TestPause(kPauseMergePlacement);
    Place(staging, artifact_root_, p[0].get<ClipId>(), p[1].get<std::string>());
    ++n;
  }
  for (const Json& p : j.value("remove", Json::array())) {
    Remove(staging, artifact_root_, p[0].get<ClipId>(), p[1].get<std::string>());
    ++n;
  }
  std::error_code ec;
  fs::remove_all(staging, ec);
  Prepare("DELETE FROM meta WHERE key = ?").Bind(1, kPlacementKey).Run();
  if (!own) spdlog::info("finished placing {} folders of a killed merge ({})", n, staging.string());
  return n;
}

}  // namespace doasido
