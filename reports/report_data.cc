#include "reports/report_data.h"

#include "core/progress.h"
#include "filters/shot_boundary.h"

namespace doasido::reports {

double Percent(std::int64_t part, std::int64_t whole) {
  return whole > 0 ? 100.0 * static_cast<double>(part) / static_cast<double>(whole) : 0.0;
}

ReportData CollectReport(Database& db, const ReportOptions& options) {
  ReportData data;
  data.database = db.path().string();
  data.generated_at = Now();
  data.pipeline = db.Pipeline();
  data.clips = db.ListClips(&data.videos);
  const auto runs = db.ReportRuns();
  data.funnel = ComputeFunnel(data.pipeline, runs, static_cast<std::int64_t>(data.clips.size()));
  data.outcomes = ComputeOutcomes(data.pipeline, runs);
  data.sources = ComputeSources(data.clips, data.outcomes);
  const auto order = FunnelOrder(data.pipeline, runs);
  data.runs = ComputeRunStats(order, runs, db.CountEvents(), db.ListEvents({"retry", "failed"}, 0),
                              options.max_failures);
  data.downloads = ComputeDownloadStats(db, runs);
  data.retarget = ComputeRetargetLadder(db, runs);

  ScoreCollector collector;
  for (const auto& stage : order) {
    collector.AddStage(stage);
    db.ForEachSummary(stage, [&](ClipId, const Json& summary) { collector.Add(stage, summary); });
  }
  data.scores = collector.Finish(options.histogram_bins);
  if (data.funnel.without_runs > 0) {
    data.notes.push_back(std::to_string(data.funnel.without_runs) +
                         " clips have no stage runs (never queued)");
  }
  return data;
}

void AddThumbnails(Database& db, ReportData& data, const ReportOptions& options) {
  // Rejected clips by (stage, reason), in clip order.
  std::map<std::pair<std::string, std::string>, std::vector<ClipId>> by_reason;
  for (const auto& [clip, o] : data.outcomes) {
    if (o.outcome == Outcome::kRejected) by_reason[{o.stage, o.reason}].push_back(clip);
  }
  std::map<ClipId, const ClipRecord*> clips;
  for (const auto& c : data.clips) clips[c.id] = &c;
  // Strips follow the funnel: stage order first, then reason.
  std::vector<std::pair<std::string, std::string>> keys;
  for (const auto& s : data.funnel.stages) {
    for (const auto& [key, ids] : by_reason) {
      if (key.first == s.stage) keys.push_back(key);
    }
  }
  const int per_reason = std::max(0, options.thumbnail.max_per_reason);
  std::uint64_t total = 0;
  for (const auto& key : keys) {
    total += std::min<std::uint64_t>(by_reason[key].size(), per_reason);
  }
  Progress progress("thumbnails", total);
  for (const auto& key : keys) {
    const auto& ids = by_reason[key];
    ThumbnailStrip strip{.stage = key.first, .verdict = "reject", .reason = key.second,
                         .clips = static_cast<std::int64_t>(ids.size())};
    for (size_t i = 0; i < ids.size() && static_cast<int>(i) < per_reason; ++i) {
      ThumbnailRequest request;
      request.clip = *clips.at(ids[i]);
      request.video_path = data.videos[ids[i]];
      request.detections = db.GetDetections(ids[i]);
      request.stage = key.first;
      request.reason = key.second;
      if (auto m = db.GetMeasurements(ids[i], filters::kShotBoundaryStageName)) {
        request.shot_summary = m->value("summary", Json());
      }
      Thumbnail t = MakeThumbnail(request, options.thumbnail);
      if (!t.note.empty()) data.notes.push_back(t.note);
      strip.items.push_back(std::move(t));
      progress.Add();
    }
    data.thumbnails.push_back(std::move(strip));
  }
  progress.Finish();
}

}  // namespace doasido::reports
