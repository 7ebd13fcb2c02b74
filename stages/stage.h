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
  // The effective parameters; their ParamHash identifies a result.
  virtual Json Params() const = 0;
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

}  // namespace doasido::stages
