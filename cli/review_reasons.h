// The review page's reason codes from the stage registry: what `doasido
// review serve` hands its server (and tests that serve the page in process).
#pragma once

#include "review/server.h"

namespace doasido::cli {

// Fills options.stage_reasons (every stage's reason codes, the filters'
// first) and options.default_reasons (each filter's reject reason).
void AddStageReasons(review::ServeOptions& options);

}  // namespace doasido::cli
