#include "stages/bundle_stage.h"

#include <unistd.h>

#include <chrono>
#include <fstream>
#include <utility>

#include <spdlog/spdlog.h>

#include "core/config_check.h"
#include "core/error.h"
#include "core/error_codes.h"
#include "core/shell_words.h"
#include "recon/bundle/bundle.h"
#include "recon/bundle/model_command.h"

namespace doasido::stages {

using namespace recon;  // the algorithms this stage runs
namespace {

// The placeholders' values for a clip, by placeholder name (without braces).
Json RequestValues(const ClipContext& context, const std::filesystem::path& dir) {
  const double fps = context.video.info ? context.video.info->fps : 0.0;
  return {{"clip", ClipName(context)},
          {"video", std::filesystem::absolute(context.video.path).string()},
          {"first_frame", context.clip.start_frame.value_or(0)},
          {"last_frame", context.clip.end_frame.value_or(-1)},
          {"fps", fps},
          {"output", std::filesystem::absolute(dir).string()}};
}

// <database folder>/logs/ from <database folder>/artifacts/<clip>/<stage>/.
std::filesystem::path LogsDir(const ClipContext& context) {
  std::filesystem::path stage_dir = context.artifact_dir.lexically_normal();
  if (!stage_dir.has_filename()) stage_dir = stage_dir.parent_path();  // a trailing '/'
  return stage_dir.parent_path().parent_path().parent_path() / "logs";
}

// The bytes a log gained since `from`, into `to` (the clip's share of a
// server log).
void CopyLogSince(const std::filesystem::path& log, std::uintmax_t from,
                  const std::filesystem::path& to) {
  std::ifstream in(log, std::ios::binary);
  in.seekg(static_cast<std::streamoff>(from));
  std::ofstream(to, std::ios::binary) << in.rdbuf();
}

// A model that wrote nothing has no output for this clip (the hands
// stage's bundle may stand in); one that wrote files but no meta.json wrote
// a broken bundle.
void CheckModelOutput(const std::filesystem::path& dir, const std::string& clip) {
  if (std::filesystem::is_regular_file(dir / "meta.json")) return;
  for (const auto& entry : std::filesystem::directory_iterator(dir)) {
    if (entry.path().filename() != "command.log") ReadClipBundle(dir, clip);
  }
}

}  // namespace

void CheckConfig(const BundleStageConfig& c, const std::string& section) {
  RequireInRange(section, "timeout_s", c.timeout_s, 0.01, 1e7);
  RequireInRange(section, "server_start_timeout_s", c.server_start_timeout_s, 0.01, 1e7);
  RequireInRange(section, "log_tail_lines", c.log_tail_lines, 0, 10000);
  if (!c.command.empty() && !c.server.empty()) {
    throw Error("bad_config", "set one of command (run per clip) and server (started once)",
                {.field = section + ".server"});
  }
}

BundleStage::BundleStage(BundleStageConfig config) : config_(std::move(config)) {
  CheckConfig(config_, kBundleStageName);
}

Json BundleStage::Params() const {
  Json params = config_;
  if (config_.server.empty()) {
    params.erase("server");
    params.erase("server_start_timeout_s");
  }
  return params;
}

void BundleStage::RunCommand(const ClipContext& context, const std::filesystem::path& dir) {
  std::string command = config_.command;
  const Json values = RequestValues(context, dir);
  for (const auto& [key, value] : values.items()) {
    if (key == "output") continue;  // last: a path may contain another placeholder's text
    ReplaceAll(command, "{" + key + "}",
               ShellQuote(value.is_string() ? value.get<std::string>()
                          : key == "fps" ? std::to_string(value.get<double>())
                                         : value.dump()));
  }
  ReplaceAll(command, "{output}", ShellQuote(dir.string()));
  const auto log = dir / "command.log";
  const CommandOutcome run =
      RunModelCommand(command, log, config_.timeout_s, config_.log_tail_lines);
  const ErrorSite site{.clip = ClipName(context), .file = log.string(), .field = "bundle.command"};
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
}

void BundleStage::RunServer(const ClipContext& context, const std::filesystem::path& dir) {
  if (!server_) {
    server_ = std::make_unique<ModelServer>(
        config_.server, LogsDir(context) / ("bundle-server-" + std::to_string(::getpid()) + ".log"),
        config_.server_start_timeout_s, config_.log_tail_lines);
  }
  std::error_code ec;
  const std::uintmax_t log_start = std::filesystem::file_size(server_->log(), ec);
  Json request = RequestValues(context, dir);
  request["type"] = "clip";
  const ServerReply reply = server_->Request(request, config_.timeout_s);
  CopyLogSince(server_->log(), ec ? 0 : log_start, dir / "command.log");
  const ErrorSite site{
      .clip = ClipName(context), .file = server_->log().string(), .field = "bundle.server"};
  switch (reply.kind) {
    case ServerReply::Kind::kDone:
      if (!reply.message["bundle"].is_string() ||
          std::filesystem::path(reply.message["bundle"].get<std::string>()).lexically_normal() !=
              std::filesystem::absolute(dir).lexically_normal()) {
        throw Error(kErrorBundleCommandFailed,
                    "the server named bundle " + reply.message["bundle"].dump() +
                        ", not the output folder " + std::filesystem::absolute(dir).string(),
                    site);
      }
      return;
    case ServerReply::Kind::kError: {
      const std::string message = reply.message.value("message", std::string("(no message)"));
      if (reply.message.value("permanent", false)) {
        throw Error(kBundleServerRefused, "the server: " + message, site);
      }
      throw Error(kErrorBundleCommandFailed, "the server: " + message + "\n" + reply.log_tail,
                  site);
    }
    case ServerReply::Kind::kTimedOut:
      throw Error(kErrorBundleTimeout,
                  "killed after " + std::to_string(config_.timeout_s) + " s: " + reply.detail +
                      "\n" + reply.log_tail,
                  site);
    case ServerReply::Kind::kDied:
    case ServerReply::Kind::kProtocol:
      throw Error(kErrorBundleCommandFailed, reply.detail + "\n" + reply.log_tail, site);
  }
}

StageResult BundleStage::Run(const ClipContext& context) {
  const std::string clip = ClipName(context);
  StageResult result;
  const auto start = std::chrono::steady_clock::now();
  // A model writes into this run's own folder; with none configured the
  // folder stays empty, so an earlier configuration's output cannot stand
  // in for the hands stage's bundle.
  std::filesystem::path model_output;
  const bool server = !config_.server.empty();
  if (!ListNamesBundle(context) && (server || !config_.command.empty())) {
    model_output = context.artifact_dir;
    std::error_code ec;
    std::filesystem::remove_all(model_output, ec);
    std::filesystem::create_directories(model_output);
    if (server) {
      RunServer(context, model_output);
    } else {
      RunCommand(context, model_output);
    }
    CheckModelOutput(model_output, clip);
  }
  const ResolvedBundle resolved = LoadClipBundle(context, model_output);
  const ClipBundle& bundle = resolved.bundle;
  result.measurements["source"] =
      server && resolved.source == kBundleFromCommand ? std::string("server") : resolved.source;
  result.measurements["hands_source"] = resolved.hands_source;
  result.measurements["object_source"] = resolved.object_source;
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

}  // namespace doasido::stages
