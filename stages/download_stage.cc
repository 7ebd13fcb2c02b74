#include "stages/download_stage.h"

#include <filesystem>

#include "core/error.h"
#include "db/database.h"

namespace doasido::stages {

using namespace ingest;  // the algorithms this stage runs
namespace {

namespace fs = std::filesystem;

std::string ClipLabel(const ClipContext& context) {
  return context.clip.external_id.empty() ? std::to_string(context.clip.id)
                                          : context.clip.external_id;
}

}  // namespace

DownloadStage::DownloadStage(DownloadConfig config) : config_(std::move(config)) {
  CheckConfig(config_, kDownloadStageName);
}

Json DownloadStage::Params() const {
  // Only what decides which file a URL becomes: timeouts and retry
  // settings may change without queueing every finished download again.
  return {{"media_dir", config_.media_dir},
          {"command", config_.command},
          {"command_hosts", config_.command_hosts},
          {"format", config_.format},
          {"max_height", config_.max_height}};
}

StageResult DownloadStage::Run(const ClipContext& context) {
  StageResult result;
  const std::string& url = context.video.path;
  if (!IsUrl(url)) {
    result.measurements = {{"summary", ToJson({.source = "local"})}};
    return result;
  }
  // artifact_dir is <database folder>/artifacts/<clip>/<stage>/.
  const fs::path root = context.artifact_dir.parent_path().parent_path().parent_path();
  const fs::path media = config_.media_dir.empty() ? root / "media" : fs::path(config_.media_dir);
  DownloadOutcome out;
  try {
    out = DownloadVideo(url, media, context.artifact_dir, config_);
  } catch (const Error& e) {
    ErrorSite site = e.site();
    site.clip = ClipLabel(context);
    throw Error(e.code(), e.message(), site);
  }
  result.measurements = {
      {"url", url},
      {"tries", out.tries},
      {"resumed_from", out.resumed_from},
      {"summary", ToJson(out.summary)},
      {Database::kVideoFileKey,
       {{"path", out.path.string()}, {"size_bytes", out.summary.size_bytes},
        {"sha256", out.sha256}}}};
  return result;
}

}  // namespace doasido::stages
