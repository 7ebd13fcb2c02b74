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

StageResult BundleStage::Run(const ClipContext& context) {
  const std::string clip = ClipName(context);
  StageResult result;
  const auto start = std::chrono::steady_clock::now();
  std::filesystem::path dir;
  if (ListNamesBundle(context)) {
    dir = BundleDir(context);
    result.measurements["source"] = "list";
  } else {
    dir = context.artifact_dir;
    if (config_.command.empty()) {
      throw PermanentError(kErrorNoBundle, "the list names no bundle and bundle.command is empty",
                  {.clip = clip, .field = "bundle.command"});
    }
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
    result.measurements["source"] = "command";
  }
  const ClipBundle bundle = ReadClipBundle(dir, clip);
  result.measurements["bundle"] = dir.string();
  result.measurements["frames"] = bundle.frames;
  result.measurements["parts"] = bundle.present;
  result.measurements["seconds"] =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  spdlog::info("{} {}: {} frames from {}", kBundleStageName, clip, bundle.frames,
               result.measurements["source"].get<std::string>());
  return result;
}

}  // namespace doasido::recon
