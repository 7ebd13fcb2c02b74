// The `bundle` queue stage: the seam where foundation models (SAM 3, MoGe,
// SAM 3D, HaWoR, BootsTAPIR, GeoCalib) hand a clip's outputs to doasido.
// Contract (docs/clip_bundle.md):
//   - A clip whose list row has a `bundle` column: that folder is validated
//     with ReadBundle; no command runs.
//   - Otherwise `command` is run by /bin/sh after replacing {video}
//     (absolute path), {first_frame}, {last_frame} (inclusive file frame
//     indices; -1 = to the end), {fps} (the probed rate, 0 if unknown),
//     {clip} (the clip's id in its list) and {output} (this stage's artifact
//     folder, <artifacts>/<clip>/bundle/, created and emptied first); each
//     value single-quoted. The command must write the clip bundle into
//     {output} and exit 0. Its stdout and stderr go to
//     {output}/command.log (ignored by the bundle reader).
//   - Server mode (`server` instead of `command`): the worker starts that
//     command once and sends it one request line per clip carrying the same
//     values (recon/bundle/model_server.h has the protocol); its stderr goes to
//     <database folder>/logs/bundle-server-<worker pid>.log and the part
//     written while a clip was served to {output}/command.log. A server that
//     dies, hangs past timeout_s or breaks the protocol is killed with its
//     group and the clip fails (bundle_command_failed / bundle_timeout, with
//     the log's tail); the next clip starts a fresh server. An "error"
//     reply fails the clip, permanently when the reply says so.
//   - Errors (clip named): bundle_command_failed (non-zero exit or signal;
//     the message holds the last log lines), bundle_timeout (killed with its
//     whole process group after timeout_s), bad_bundle (ReadBundle's
//     complaint naming file and field), no_bundle (no command configured,
//     no bundle named and no hands found by the hands stage). bad_bundle
//     and no_bundle are permanent (core/error_codes.h: the worker does not
//     retry them), like bundle_server_refused (a server's error reply that
//     says "permanent": true); a
//     failed or timed-out command may be transient (a busy GPU) and is
//     retried.
//   - Neither list bundle nor command output (a command that exits 0 and
//     writes nothing has no output for the clip): the hands stage's hand-only bundle
//     (<artifacts>/<clip>/hands/) is the clip's bundle. A list or command
//     bundle without hands gets the hands stage's hands
//     (stages/clip_inputs.h LoadClipBundle, which every later stage uses).
//     The hands stage's bundle gets the objects stage's object (mesh and
//     metric poses) when that stage found one; a list or command bundle
//     keeps its own object, or none.
// Measurements: source ("list", "command" or "hands"), hands_source
// ("bundle", "hands" or "none"), object_source ("bundle", "objects" or
// "none"), producers, seconds, frames, parts found.
#pragma once

#include <memory>
#include <string>

#include "core/config.h"
#include "recon/bundle/model_server.h"
#include "stages/clip_inputs.h"
#include "stages/stage.h"

namespace doasido::stages {

struct BundleStageConfig {
  std::string command;       // empty: only clips whose list names a bundle pass
  std::string server;        // a model server (at most one of command and server)
  double timeout_s = 3600;   // wall clock per clip
  double server_start_timeout_s = 1800;  // a server's load, until its ready line
  int log_tail_lines = 20;   // lines of output quoted in a failure
};
NLOHMANN_DEFINE_TYPE_NON_INTRUSIVE_WITH_DEFAULT(BundleStageConfig, command, server, timeout_s,
                                                server_start_timeout_s, log_tail_lines)
void CheckConfig(const BundleStageConfig& c, const std::string& section);

// Error codes of the stage.
inline constexpr const char* kErrorBundleCommandFailed = "bundle_command_failed";
inline constexpr const char* kErrorBundleTimeout = "bundle_timeout";

class BundleStage : public Stage {
 public:
  explicit BundleStage(BundleStageConfig config = {});
  std::string Name() const override { return recon::kBundleStageName; }
  // The config; the server keys only in server mode, so that configs
  // written before server mode keep their parameter hash.
  Json Params() const override;
  StageResult Run(const ClipContext& context) override;

 private:
  // Writes the bundle into `dir` with the command, or the server.
  void RunCommand(const ClipContext& context, const std::filesystem::path& dir);
  void RunServer(const ClipContext& context, const std::filesystem::path& dir);

  BundleStageConfig config_;
  std::unique_ptr<recon::ModelServer> server_;  // started on the first clip
};

}  // namespace doasido::stages
