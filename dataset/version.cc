#include "dataset/version.h"

#include <fstream>

#include "core/error.h"

namespace doasido::dataset {
namespace {

namespace fs = std::filesystem;

// Reads j[key] as T, or throws Error("bad_manifest") naming `where.key`.
template <typename T>
T Get(const Json& j, const char* key, const std::string& where) {
  const std::string field = where.empty() ? key : where + "." + key;
  if (!j.is_object() || !j.contains(key)) {
    throw Error("bad_manifest", "missing member", {.field = field});
  }
  try {
    return j.at(key).get<T>();
  } catch (const Json::exception&) {
    throw Error("bad_manifest", "member has the wrong type", {.field = field});
  }
}

template <typename T>
std::optional<T> GetOptional(const Json& j, const char* key, const std::string& where) {
  if (!j.contains(key) || j.at(key).is_null()) return std::nullopt;
  return Get<T>(j, key, where);
}

template <typename T>
Json OrNull(const std::optional<T>& v) {
  return v ? Json(*v) : Json(nullptr);
}

Json ToJson(const StageProvenance& s) {
  return {{"stage", s.stage}, {"param_hash", s.param_hash}, {"verdict", s.verdict},
          {"reason", s.reason}, {"source", s.source}, {"finished_at", OrNull(s.finished_at)}};
}

StageProvenance StageFromJson(const Json& j, const std::string& at) {
  return {Get<std::string>(j, "stage", at), Get<std::string>(j, "param_hash", at),
          Get<std::string>(j, "verdict", at), Get<std::string>(j, "reason", at),
          Get<std::string>(j, "source", at), GetOptional<double>(j, "finished_at", at)};
}

Json ToJson(const Episode& e) {
  Json stages = Json::array();
  for (const StageProvenance& s : e.stages) stages.push_back(ToJson(s));
  Json verification = nullptr;
  if (e.verification) {
    verification = {{"reviewer", e.verification->reviewer}, {"at", e.verification->at},
                    {"reason", e.verification->reason}};
  }
  return {{"id", e.id},
          {"index", e.index},
          {"clip_id", e.clip_id},
          {"external_id", e.external_id},
          {"video", e.video},
          {"video_key", e.video_key},
          {"span",
           {{"start_frame", OrNull(e.start_frame)},
            {"end_frame", OrNull(e.end_frame)},
            {"start_s", OrNull(e.start_s)},
            {"end_s", OrNull(e.end_s)}}},
          {"source", {{"list", e.source_list}, {"line", e.source_line}}},
          {"task", e.task},
          {"split", e.split},
          {"trajectory_stage", e.trajectory_stage},
          {"frames", e.frames},
          {"fps", e.fps},
          {"embodiment", e.embodiment},
          {"hand_only", e.hand_only},
          {"stages", stages},
          {"upstream", e.upstream},
          {"verification", verification},
          {"metadata", e.metadata}};
}

Episode EpisodeFromJson(const Json& j, const std::string& where) {
  Episode e;
  e.id = Get<std::string>(j, "id", where);
  e.index = Get<std::int64_t>(j, "index", where);
  e.clip_id = Get<std::int64_t>(j, "clip_id", where);
  e.external_id = Get<std::string>(j, "external_id", where);
  e.video = Get<std::string>(j, "video", where);
  e.video_key = Get<std::string>(j, "video_key", where);
  const Json span = Get<Json>(j, "span", where);
  e.start_frame = GetOptional<std::int64_t>(span, "start_frame", where + ".span");
  e.end_frame = GetOptional<std::int64_t>(span, "end_frame", where + ".span");
  e.start_s = GetOptional<double>(span, "start_s", where + ".span");
  e.end_s = GetOptional<double>(span, "end_s", where + ".span");
  const Json source = Get<Json>(j, "source", where);
  e.source_list = Get<std::string>(source, "list", where + ".source");
  e.source_line = Get<long>(source, "line", where + ".source");
  e.task = Get<std::string>(j, "task", where);
  e.split = Get<std::string>(j, "split", where);
  e.trajectory_stage = Get<std::string>(j, "trajectory_stage", where);
  e.frames = Get<std::int64_t>(j, "frames", where);
  e.fps = Get<double>(j, "fps", where);
  e.embodiment = Get<std::string>(j, "embodiment", where);
  e.hand_only = j.contains("hand_only") && Get<bool>(j, "hand_only", where);  // absent in older manifests
  const Json stages = Get<Json>(j, "stages", where);
  for (size_t i = 0; i < stages.size(); ++i) {
    e.stages.push_back(StageFromJson(stages[i], where + ".stages[" + std::to_string(i) + "]"));
  }
  if (j.contains("verification") && !j["verification"].is_null()) {
    const Json& v = j["verification"];
    const std::string at = where + ".verification";
    e.verification = Verification{Get<std::string>(v, "reviewer", at), Get<double>(v, "at", at),
                                  Get<std::string>(v, "reason", at)};
  }
  e.metadata = j.value("metadata", Json::object());
  e.upstream = j.value("upstream", Json());
  return e;
}

}  // namespace

const char* ToString(Selection s) {
  switch (s) {
    case Selection::kVerified: return "verified";
    case Selection::kSuccess: return "success";
    case Selection::kAll: return "all";
  }
  return "?";
}

Selection ParseSelection(const std::string& text) {
  for (Selection s : {Selection::kVerified, Selection::kSuccess, Selection::kAll}) {
    if (text == ToString(s)) return s;
  }
  throw Error("bad_option", "'" + text + "' is not one of verified, success, all",
              {.field = "--select"});
}

Json ToJson(const Manifest& m) {
  Json splits = Json::array();
  for (const auto& [name, fraction] : m.split_fractions) splits.push_back({name, fraction});
  Json episodes = Json::array();
  for (const Episode& e : m.episodes) episodes.push_back(ToJson(e));
  Json excluded = Json::array();
  for (const Exclusion& x : m.excluded) {
    excluded.push_back({{"clip_id", x.clip_id}, {"external_id", x.external_id},
                        {"decided_by", ToJson(x.decided_by)}, {"why", x.why}});
  }
  Json files = Json::array();
  for (const FileEntry& f : m.files) {
    files.push_back({{"path", f.path}, {"sha256", f.sha256}, {"size", f.size}});
  }
  return {{"format", kManifestFormat},
          {"format_version", kManifestFormatVersion},
          {"name", m.name},
          {"version", m.version},
          {"parent", m.parent.empty() ? Json(nullptr) : Json(m.parent)},
          {"created_at", m.created_at},
          {"tool", {{"version", m.tool_version}, {"revision", m.tool_revision}}},
          {"database", m.database},
          {"selection", ToString(m.selection)},
          {"splits", splits},
          {"seed", m.seed},
          {"trajectory_stage", m.trajectory_stage},
          {"episodes", episodes},
          {"excluded", excluded},
          {"allow_stale", m.allow_stale},
          {"stale", m.stale},
          {"files", files}};
}

Manifest ManifestFromJson(const Json& j) {
  if (Get<std::string>(j, "format", "") != kManifestFormat) {
    throw Error("bad_manifest", "not a doasido dataset manifest", {.field = "format"});
  }
  if (Get<int>(j, "format_version", "") > kManifestFormatVersion) {
    throw Error("bad_manifest", "written by a newer doasido", {.field = "format_version"});
  }
  Manifest m;
  m.name = Get<std::string>(j, "name", "");
  m.version = Get<std::string>(j, "version", "");
  m.parent = GetOptional<std::string>(j, "parent", "").value_or("");
  m.created_at = Get<double>(j, "created_at", "");
  const Json tool = Get<Json>(j, "tool", "");
  m.tool_version = Get<std::string>(tool, "version", "tool");
  m.tool_revision = Get<std::string>(tool, "revision", "tool");
  m.database = Get<std::string>(j, "database", "");
  try {
    m.selection = ParseSelection(Get<std::string>(j, "selection", ""));
  } catch (const Error&) {
    throw Error("bad_manifest", "unknown selection", {.field = "selection"});
  }
  for (const Json& s : Get<Json>(j, "splits", "")) {
    m.split_fractions.emplace_back(s.at(0).get<std::string>(), s.at(1).get<double>());
  }
  m.seed = Get<std::int64_t>(j, "seed", "");
  const Json episodes = Get<Json>(j, "episodes", "");
  for (size_t i = 0; i < episodes.size(); ++i) {
    m.episodes.push_back(EpisodeFromJson(episodes[i], "episodes[" + std::to_string(i) + "]"));
  }
  m.trajectory_stage = Get<std::string>(j, "trajectory_stage", "");
  m.allow_stale = j.value("allow_stale", false);
  m.stale = j.value("stale", std::vector<std::string>{});
  const Json excluded = Get<Json>(j, "excluded", "");
  for (size_t i = 0; i < excluded.size(); ++i) {
    const std::string at = "excluded[" + std::to_string(i) + "]";
    m.excluded.push_back({Get<std::int64_t>(excluded[i], "clip_id", at),
                          Get<std::string>(excluded[i], "external_id", at),
                          StageFromJson(Get<Json>(excluded[i], "decided_by", at), at + ".decided_by"),
                          Get<std::string>(excluded[i], "why", at)});
  }
  const Json files = Get<Json>(j, "files", "");
  for (size_t i = 0; i < files.size(); ++i) {
    const std::string at = "files[" + std::to_string(i) + "]";
    m.files.push_back({Get<std::string>(files[i], "path", at),
                       Get<std::string>(files[i], "sha256", at),
                       Get<std::int64_t>(files[i], "size", at)});
  }
  return m;
}

Manifest ReadManifest(const fs::path& version_dir) {
  const fs::path path = version_dir / kManifestFile;
  std::ifstream in(path, std::ios::binary);
  if (!in) throw Error("io", "cannot read the manifest", {.file = path.string()});
  try {
    return ManifestFromJson(Json::parse(in));
  } catch (const Json::parse_error& e) {
    throw Error("bad_manifest", std::string("not JSON: ") + e.what(), {.file = path.string()});
  } catch (const Error& e) {
    ErrorSite site = e.site();
    site.file = path.string();
    throw Error(e.code(), e.message(), site);
  }
}

}  // namespace doasido::dataset
