// Database members of artifacts (database.h): the artifact root owned by
// this database, the folder layout of a clip's stage outputs, publishing a
// run's folder, and the one lookup every reader of artifacts goes through.
#include <sqlite3.h>
#include <unistd.h>

#include <algorithm>
#include <cstdint>
#include <fstream>

#include "db/database.h"
#include "db/statement.h"

namespace doasido {
namespace {

namespace fs = std::filesystem;

// The uuid named in a root's owner file, or "" when it has none.
std::string OwnerOf(const fs::path& root) {
  std::ifstream in(root / Database::kArtifactOwnerFile);
  if (!in) return "";
  const Json j = Json::parse(in, nullptr, false);
  if (j.is_discarded() || !j.is_object() || !j.contains("uuid") || !j["uuid"].is_string()) {
    return "?";  // unreadable: nobody's that we can prove, so not ours either
  }
  return j["uuid"].get<std::string>();
}

std::string OwnerPath(const fs::path& root) {
  std::ifstream in(root / Database::kArtifactOwnerFile);
  const Json j = Json::parse(in, nullptr, false);
  return j.is_object() && j.contains("database") && j["database"].is_string()
             ? j["database"].get<std::string>()
             : std::string("another database");
}

// Writes the owner file naming database `uuid` at `database` (renamed into
// place, so a reader never sees half of one).
void WriteOwnerFile(const fs::path& root, const std::string& uuid, const fs::path& database) {
  std::error_code ec;
  const fs::path owner = root / Database::kArtifactOwnerFile;
  // One temporary per process: workers of one run claim the folder at once.
  const fs::path temp = owner.string() + ".tmp-" + std::to_string(::getpid());
  {
    std::ofstream out(temp, std::ios::trunc);
    out << Json{{"uuid", uuid}, {"database", database.string()}}.dump() << "\n";
    if (!out) throw Error("io", "cannot write the artifact folder's owner file", {.file = temp.string()});
  }
  fs::rename(temp, owner, ec);
  if (ec) {
    fs::remove(temp, ec);
    throw Error("io", "cannot write: " + ec.message(), {.file = owner.string()});
  }
}

// Makes `root` database `uuid`'s when no database owns it: the folder and
// its owner file, created at once (link(2) refuses an existing name, so of
// two databases created together one gets it). True when `uuid` owns it.
bool TryClaim(const fs::path& root, const std::string& uuid, const fs::path& database) {
  std::error_code ec;
  fs::create_directories(root, ec);
  const fs::path owner = root / Database::kArtifactOwnerFile;
  const fs::path temp = owner.string() + ".claim-" + std::to_string(::getpid());
  {
    std::ofstream out(temp, std::ios::trunc);
    out << Json{{"uuid", uuid}, {"database", database.string()}}.dump() << "\n";
    if (!out) throw Error("io", "cannot write the artifact folder's owner file", {.file = temp.string()});
  }
  ::link(temp.c_str(), owner.c_str());  // EEXIST: someone's already; read below
  fs::remove(temp, ec);
  return OwnerOf(root) == uuid;
}

// Whether `folder` holds a doasido database other than `self`: a SQLite
// file (header "SQLite format 3") whose application_id (big-endian, bytes
// 68-71 of the header) is doasido's. Such a database may record
// "artifacts" as its root without having claimed it yet (made before roots
// were claimed at creation), so a new neighbour does not take that name.
bool HasOtherDatabase(const fs::path& folder, const fs::path& self) {
  std::error_code ec;
  for (const auto& entry : fs::directory_iterator(folder, ec)) {
    if (entry.path() == self || !entry.is_regular_file(ec)) continue;
    std::ifstream in(entry.path(), std::ios::binary);
    unsigned char header[72] = {};
    if (!in.read(reinterpret_cast<char*>(header), sizeof header)) continue;
    if (std::string(reinterpret_cast<char*>(header), 15) != "SQLite format 3") continue;
    const std::uint32_t id = (std::uint32_t{header[68]} << 24) | (std::uint32_t{header[69]} << 16) |
                             (std::uint32_t{header[70]} << 8) | header[71];
    if (id == static_cast<std::uint32_t>(Database::kApplicationId)) return true;
  }
  return false;
}

// Decided and claimed when the database is created, so that databases made
// side by side never share a root whichever runs first: the folder's
// `artifacts` for the first database in it, else the database's own
// `<stem>.artifacts` (`<file name>.artifacts` when that too is taken).
std::string ClaimNewArtifactRoot(const fs::path& root, const fs::path& database, const std::string& uuid) {
  std::vector<std::string> candidates = {database.stem().string() + ".artifacts",
                                         database.filename().string() + ".artifacts"};
  if (!HasOtherDatabase(root, database)) candidates.insert(candidates.begin(), "artifacts");
  for (const auto& candidate : candidates) {
    if (TryClaim(root / candidate, uuid, database)) return candidate;
  }
  throw Error("foreign_artifacts", "every artifact folder this database could take (" + candidates.front() +
                                       ", ...) belongs to another database; put the database in its own folder");
}

const std::string kWorkTag = ".run-";
const std::string kAsideTag = ".old-";

}  // namespace

void Database::OpenArtifactRoot() {
  std::optional<std::string> stored = GetMeta(kArtifactRootKey);
  const std::string uuid = Uuid();
  if (!stored) {
    if (read_only_) {
      // A read-only database claims nothing: it reads where it would have put it.
      const std::string owner = OwnerOf(root_ / "artifacts");
      stored = owner.empty() || owner == uuid ? "artifacts" : path_.stem().string() + ".artifacts";
    } else {
      stored = ClaimNewArtifactRoot(root_, path_, uuid);
      Transaction tx(*this);
      SetMeta(kArtifactRootKey, *stored);
      tx.Commit();
    }
  }
  artifact_root_ = (root_ / *stored).lexically_normal();
  const std::string owner = OwnerOf(artifact_root_);
  if (owner == uuid && OwnerPath(artifact_root_) != path_.string()) {
    // The database and its folder were moved or copied together: the owner
    // file names where it is now (best effort; the uuid is what is checked).
    try {
      WriteOwnerFile(artifact_root_, uuid, path_);
    } catch (const Error&) {
    }
  }
  if (!owner.empty() && owner != uuid) {
    throw Error("foreign_artifacts",
                "the artifact folder " + artifact_root_.string() + " belongs to " +
                    OwnerPath(artifact_root_) + " (its " + kArtifactOwnerFile +
                    " names database " + owner + ", this one is " + uuid +
                    "); move one of the databases into its own folder");
  }
}

void Database::ClaimArtifactRoot() {
  std::error_code ec;
  if (fs::exists(artifact_root_ / kArtifactOwnerFile, ec)) return;
  fs::create_directories(artifact_root_, ec);
  WriteOwnerFile(artifact_root_, Uuid(), path_);
}

fs::path Database::ArtifactDir(ClipId clip, const std::string& stage) const {
  return artifact_root_ / std::to_string(clip) / stage;
}

fs::path Database::ArtifactWorkDir(const Claim& claim) const {
  return artifact_root_ / std::to_string(claim.clip_id) /
         ("." + claim.stage + kWorkTag + std::to_string(claim.run_id) + "-" +
          std::to_string(claim.attempts));
}

void Database::RemoveArtifactLeftovers(ClipId clip, const std::string& stage) {
  const fs::path clip_dir = artifact_root_ / std::to_string(clip);
  std::error_code ec;
  for (const std::string& tag : {kWorkTag, kAsideTag}) {
    const std::string prefix = "." + stage + tag;
    for (const auto& entry : fs::directory_iterator(clip_dir, ec)) {
      if (entry.path().filename().string().rfind(prefix, 0) == 0) fs::remove_all(entry.path(), ec);
    }
  }
}

void Database::PublishArtifacts(const Claim& claim) {
  const fs::path work = ArtifactWorkDir(claim);
  const fs::path target = ArtifactDir(claim.clip_id, claim.stage);
  const fs::path aside = target.parent_path() /
                         ("." + claim.stage + kAsideTag + std::to_string(claim.run_id) + "-" +
                          std::to_string(claim.attempts));
  std::error_code ec;
  if (fs::exists(target, ec)) {
    fs::remove_all(aside, ec);
    fs::rename(target, aside, ec);
    if (ec) {
      throw Error("io", "cannot move the previous output aside: " + ec.message(),
                  {.clip = std::to_string(claim.clip_id), .file = target.string()});
    }
  }
  if (fs::is_directory(work, ec) && fs::is_empty(work, ec)) {
    fs::remove(work, ec);
  } else if (fs::exists(work, ec)) {
    fs::rename(work, target, ec);
    if (ec) {
      throw Error("io", "cannot publish the run's folder: " + ec.message(),
                  {.clip = std::to_string(claim.clip_id), .file = work.string()});
    }
  }
  fs::remove_all(aside, ec);
  // A clip folder no stage wrote into is not left behind.
  if (fs::is_directory(target.parent_path(), ec) && fs::is_empty(target.parent_path(), ec)) {
    fs::remove(target.parent_path(), ec);
  }
}

std::optional<Database::RunOutput> Database::RecordedOutput(ClipId clip, const std::string& stage,
                                                            bool allow_flag, std::string* why) {
  auto& q = Prepare(
      "SELECT id, state, IFNULL(verdict, ''), IFNULL(reason, ''), IFNULL(param_hash, '')"
      " FROM stage_runs WHERE clip_id = ? AND stage = ?");
  q.Bind(1, clip).Bind(2, stage);
  std::optional<RunOutput> out;
  std::string state;
  if (q.Step()) {
    out = RunOutput{q.Int(0), clip, stage, ArtifactDir(clip, stage), q.Text(2), q.Text(3), q.Text(4)};
    state = q.Text(1);
  }
  q.Reset();
  auto refuse = [&](const std::string& text) -> std::optional<RunOutput> {
    if (why) *why = text;
    return std::nullopt;
  };
  const std::string name = "clip " + std::to_string(clip) + "'s " + stage + " run";
  if (!out) return refuse(name + ": none recorded in " + path_.string());
  const std::string run = name + " " + std::to_string(out->run_id);
  if (state != "done") return refuse(run + " is " + state + ", not done");
  if (out->verdict != "pass" && !(allow_flag && out->verdict == "flag")) {
    return refuse(run + " gave " + out->verdict +
                  (out->reason.empty() ? "" : " (" + out->reason + ")") +
                  (allow_flag ? "" : ", not pass"));
  }
  std::error_code ec;
  if (!fs::is_directory(out->dir, ec)) {
    return refuse(run + " is recorded done but its folder is missing: " + out->dir.string());
  }
  return out;
}

std::vector<std::string> Database::StagesAfter(const std::string& stage) {
  const auto& stages = Pipeline();
  const auto it = std::find(stages.begin(), stages.end(), stage);
  if (it == stages.end()) return {};
  return {it + 1, stages.end()};
}

std::vector<std::pair<std::string, std::string>> Database::ListArtifacts(ClipId clip) {
  auto& q = Prepare("SELECT stage, path FROM artifacts WHERE clip_id = ? ORDER BY id");
  q.Bind(1, clip);
  std::vector<std::pair<std::string, std::string>> out;
  while (q.Step()) out.emplace_back(q.Text(0), q.Text(1));
  q.Reset();
  return out;
}

void Database::DiscardArtifacts(ClipId clip, const std::vector<std::string>& stages) {
  std::error_code ec;
  for (const std::string& stage : stages) {
    Prepare("DELETE FROM artifacts WHERE clip_id = ? AND stage = ?").Bind(1, clip).Bind(2, stage).Run();
    fs::remove_all(ArtifactDir(clip, stage), ec);
  }
}

}  // namespace doasido
