// The contract every queue stage implements.
//
// A stage is a pure function of one clip and its parameters: the worker
// loads a ClipContext from the database, calls Run, and records the
// StageResult in the same transaction that completes the stage run (both
// records are db/stage_records.h: what the database loads and stores). Stages
// never open the database and never call each other; they meet through the
// database (detections, earlier stages' measurements) and the clip's
// artifact folder.
#pragma once

#include <optional>
#include <string>

#include "core/config.h"
#include "db/stage_records.h"

namespace doasido::stages {

class Stage {
 public:
  virtual ~Stage() = default;
  virtual std::string Name() const = 0;
  // The effective parameters; with Revision, what identifies a result
  // (ResultHash).
  virtual Json Params() const = 0;
  // Bumped when a change of code changes what the stage makes from the
  // same parameters (a bug fixed), so that earlier results are made again
  // as after a change of parameters. 1: the hash is the parameters' alone.
  virtual int Revision() const { return 1; }
  // Runs on one clip. Throws doasido::Error for bad input; the worker
  // records the message and retries up to the attempt limit.
  virtual StageResult Run(const ClipContext& context) = 0;
  // Once per worker process, before its first clip: what every clip would
  // otherwise pay on first use (the hand models' graphs). Default: nothing.
  virtual void Prepare() {}
  // Re-decides a verdict from stored measurements (for re-thresholding).
  // Stages whose verdict is not a threshold return nullopt.
  virtual std::optional<StageResult> Redecide(const Json& measurements) const {
    (void)measurements;
    return std::nullopt;
  }
};

// What identifies a stage's result: ParamHash of its parameters, or of
// {"params": ..., "revision": N} once Revision() > 1 (so revision 1 keeps
// the hashes recorded before revisions existed).
inline std::string ResultHash(const Stage& stage) {
  const int revision = stage.Revision();
  if (revision <= 1) return ParamHash(stage.Params());
  return ParamHash(Json{{"params", stage.Params()}, {"revision", revision}});
}

}  // namespace doasido::stages
