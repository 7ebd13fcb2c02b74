// An Error that a retry cannot fix (a 404, a video the site says is gone,
// a bad configuration for this input). The worker fails such a run at once
// instead of spending its remaining attempts on it; everything else about
// it is an ordinary doasido::Error (code, message, site).
#pragma once

#include <string>
#include <utility>

#include "core/error.h"

namespace doasido {

class PermanentError : public Error {
 public:
  PermanentError(std::string code, std::string message, ErrorSite site = {})
      : Error(std::move(code), std::move(message), std::move(site)) {}
};

}  // namespace doasido
