#include "recon/bundle_stage.h"

#include <chrono>
#include <utility>

#include <spdlog/spdlog.h>

#include "core/config_check.h"
#include "core/error.h"
#include "core/permanent_error.h"
#include "core/shell_words.h"
#include "recon/bundle.h"
#include "recon/model_command.h"

namespace doasido::recon {
void CheckConfig(const BundleStageConfig& c, const std::string& section) {
  RequireInRange(section, "timeout_s", c.timeout_s, 0.01, 1e7);
  RequireInRange(section, "log_tail_lines", c.log_tail_lines, 0, 10000);
}

BundleStage::BundleStage(BundleStageConfig config) : config_(std::move(config)) {
  CheckConfig(config_, kBundleStageName);
}

void BundleStage::RunCommand(const ClipContext& context, const std::string& clip) const {
  const std::filesystem::path dir = context.artifact_dir;
  std::error_code ec;
  std::filesystem::remove_all(dir, ec);
  std::filesystem::create_directories(dir);
  std::string command = config_.command;
  const double fps = context.video.info ? context.video.info->fps : 0.0;
  const std::pair<const char*, std::string> values[] = {
      {"{video}", std::filesystem::absolute(context.video.path).string()},
      {"{first_frame}", std::to_string(context.clip.start_frame.value_or(0))},
      {"{last_frame}", std::to_string(context.clip.end_frame.value_or(-1))},
      {"{fps}", std::to_string(fps)},
      {"{clip}", clip}};
  for (const auto& [key, value] : values) ReplaceAll(command, key, ShellQuote(value));
  ReplaceAll(command, "{output}", ShellQuote(dir.string()));
  const auto log = dir / "command.log";
  const CommandOutcome run =
      RunModelCommand(command, log, config_.timeout_s, config_.log_tail_lines);
  const ErrorSite site{.clip = clip, .file = log.string(), .field = "bundle.command"};
  if (run.timed_out) {
    throw Error(kErrorBundleTimeout,
                "killed after " + std::to_string(config_.timeout_s) + " s: " + command, site);
  }
  if (run.exit_code != 0) {
    throw Error(kErrorBundleCommandFailed,
                (run.signal ? "signal " + std::to_string(run.signal)
                            : "exit status " + std::to_string(run.exit_code)) +
                    ": " + command + "\n" + run.log_tail,
                site);
  }
  // A command that wrote nothing has no model output for this clip (the
  // hands stage's bundle may stand in); one that wrote files but no
  // meta.json wrote a broken bundle.
  if (std::filesystem::is_regular_file(dir / "meta.json")) return;
  for (const auto& entry : std::filesystem::directory_iterator(dir)) {
    if (entry.path().filename() != "command.log") ReadClipBundle(dir, clip);
  }
}

StageResult BundleStage::Run(const ClipContext& context) {
  const std::string clip = ClipName(context);
  StageResult result;
  const auto start = std::chrono::steady_clock::now();
  if (!ListNamesBundle(context) && !config_.command.empty()) RunCommand(context, clip);
  if (!ListNamesBundle(context) && config_.command.empty()) {
    // This stage's own folder: a model command's output from an earlier
    // configuration must not stand in for the hands stage's bundle.
    std::error_code ec;
    std::filesystem::remove_all(context.artifact_dir, ec);
  }
  const ResolvedBundle resolved = LoadClipBundle(context);
  const ClipBundle& bundle = resolved.bundle;
  result.measurements["source"] = resolved.source;
  result.measurements["hands_source"] = resolved.hands_source;
  result.measurements["producers"] = bundle.producers;
  result.measurements["bundle"] = resolved.dir.string();
  result.measurements["frames"] = bundle.frames;
  result.measurements["parts"] = bundle.present;
  result.measurements["seconds"] =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  spdlog::info("{} {}: {} frames from {} (hands: {})", kBundleStageName, clip, bundle.frames,
               resolved.source, resolved.hands_source);
  return result;
}

}  // namespace doasido::recon
