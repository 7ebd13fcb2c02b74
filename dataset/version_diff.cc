#include "dataset/version_diff.h"

#include <map>

namespace doasido::dataset {
namespace {

std::string Short(const std::string& hash) { return hash.substr(0, 10); }

std::string Verdict(const StageProvenance& s) {
  std::string text = s.verdict.empty() ? "unfinished" : s.verdict;
  if (!s.reason.empty()) text += " (" + s.reason + ")";
  return text;
}

std::string By(const std::string& source) {
  if (source == "rethreshold") return "re-threshold";
  if (source == "human") return "a person's verdict";
  return "the stage";
}

// Why one stage's say differs between versions, or empty when it does not.
std::string Compare(const StageProvenance& old, const StageProvenance& now) {
  if (old.param_hash != now.param_hash) {
    return now.stage + ": " + (now.source == "rethreshold" ? "re-threshold, " : "") +
           "new parameters (" + Short(old.param_hash) + " -> " + Short(now.param_hash) + "), " +
           Verdict(old) + " -> " + Verdict(now);
  }
  if (old.verdict != now.verdict || old.reason != now.reason || old.source != now.source) {
    return now.stage + ": " + By(now.source) + ", " + Verdict(old) + " -> " + Verdict(now);
  }
  return "";
}

const StageProvenance* Find(const std::vector<StageProvenance>& stages, const std::string& stage) {
  for (const StageProvenance& s : stages) {
    if (s.stage == stage) return &s;
  }
  return nullptr;
}

// Reasons an episode's stages differ: a changed verdict, or new parameters
// alone when `files_changed` (a stage that re-ran and made other files).
void CompareStages(const std::vector<StageProvenance>& old, const std::vector<StageProvenance>& now,
                   bool files_changed, std::vector<std::string>& reasons) {
  for (const StageProvenance& s : now) {
    const StageProvenance* before = Find(old, s.stage);
    if (!before) {
      reasons.push_back(s.stage + ": new stage, " + Verdict(s));
    } else if (before->verdict != s.verdict || before->reason != s.reason) {
      reasons.push_back(Compare(*before, s));
    } else if (files_changed && before->param_hash != s.param_hash) {
      reasons.push_back(s.stage + ": new parameters (" + Short(before->param_hash) + " -> " +
                        Short(s.param_hash) + ")");
    }
  }
}

std::map<std::string, std::string> FilesOf(const Manifest& m, const std::string& episode_id) {
  std::map<std::string, std::string> out;
  const std::string prefix = std::string(kEpisodesFolder) + "/" + episode_id + "/";
  for (const FileEntry& f : m.files) {
    if (f.path.compare(0, prefix.size(), prefix) == 0) out[f.path.substr(prefix.size())] = f.sha256;
  }
  return out;
}

}  // namespace

const char* ToString(EpisodeChange::Kind kind) {
  switch (kind) {
    case EpisodeChange::Kind::kAdded: return "added";
    case EpisodeChange::Kind::kRemoved: return "removed";
    case EpisodeChange::Kind::kChanged: return "changed";
  }
  return "?";
}

std::vector<EpisodeChange> DiffVersions(const Manifest& a, const Manifest& b) {
  std::map<std::int64_t, const Episode*> in_a, in_b;
  std::map<std::int64_t, const Exclusion*> out_a, out_b;
  for (const Episode& e : a.episodes) in_a[e.clip_id] = &e;
  for (const Episode& e : b.episodes) in_b[e.clip_id] = &e;
  for (const Exclusion& x : a.excluded) out_a[x.clip_id] = &x;
  for (const Exclusion& x : b.excluded) out_b[x.clip_id] = &x;

  std::map<std::int64_t, EpisodeChange> changes;
  for (const auto& [clip, e] : in_a) {
    if (in_b.count(clip)) continue;
    EpisodeChange c{EpisodeChange::Kind::kRemoved, clip, e->external_id, {}};
    const Exclusion* x = out_b.count(clip) ? out_b[clip] : nullptr;
    if (!x) {
      c.reasons.push_back("the clip is not in " + b.version + "'s database");
    } else {
      const StageProvenance* before = Find(e->stages, x->decided_by.stage);
      const std::string why = before ? Compare(*before, x->decided_by) : "";
      c.reasons.push_back(why.empty() ? x->why : why);
    }
    changes[clip] = std::move(c);
  }
  for (const auto& [clip, e] : in_b) {
    const auto old = in_a.find(clip);
    if (old == in_a.end()) {
      EpisodeChange c{EpisodeChange::Kind::kAdded, clip, e->external_id, {}};
      if (const auto x = out_a.find(clip); x != out_a.end()) {
        const StageProvenance* now = Find(e->stages, x->second->decided_by.stage);
        const std::string why = now ? Compare(x->second->decided_by, *now) : "";
        c.reasons.push_back(why.empty() ? "was left out of " + a.version + ": " + x->second->why
                                        : why);
      } else {
        c.reasons.push_back("new clip");
      }
      changes[clip] = std::move(c);
      continue;
    }
    EpisodeChange c{EpisodeChange::Kind::kChanged, clip, e->external_id, {}};
    const bool files_changed = FilesOf(a, old->second->id) != FilesOf(b, e->id);
    CompareStages(old->second->stages, e->stages, files_changed, c.reasons);
    const auto& va = old->second->verification;
    const auto& vb = e->verification;
    if (va.has_value() != vb.has_value() || (va && (va->reviewer != vb->reviewer || va->at != vb->at))) {
      c.reasons.push_back(vb ? "verified by " + vb->reviewer : "no longer verified");
    }
    if (old->second->split != e->split) {
      c.reasons.push_back("split " + old->second->split + " -> " + e->split);
    }
    if (files_changed) c.reasons.push_back("files changed");
    if (!c.reasons.empty()) changes[clip] = std::move(c);
  }
  std::vector<EpisodeChange> out;
  for (auto& [clip, c] : changes) out.push_back(std::move(c));
  return out;
}

}  // namespace doasido::dataset
