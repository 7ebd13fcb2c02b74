// The `download` queue stage: a clip whose video is a URL gets the video
// fetched into the database's media folder before `probe` reads it
// (ingest/download.h DownloadVideo: how, with which error codes); a local
// video passes at once. The result hands the file to the worker in the
// measurements member Database::kVideoFileKey, so the videos row records
// local_path, size_bytes, sha256 and downloaded_at, and later stages
// (probe first) see the local path in their ClipContext. Measurements: url,
// tries, resumed_from, summary (ingest::DownloadSummary).
#pragma once

#include <string>

#include "core/config.h"
#include "ingest/download.h"
#include "stages/stage.h"

namespace doasido::stages {

class DownloadStage : public Stage {
 public:
  explicit DownloadStage(ingest::DownloadConfig config = {});
  std::string Name() const override { return ingest::kDownloadStageName; }
  Json Params() const override;
  StageResult Run(const ClipContext& context) override;

 private:
  ingest::DownloadConfig config_;
};

}  // namespace doasido::stages
