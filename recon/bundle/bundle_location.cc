#include "recon/bundle/bundle_location.h"

#include "core/permanent_error.h"

namespace doasido::recon {

ClipBundle ReadClipBundle(const std::filesystem::path& dir, const std::string& clip) {
  try {
    return ReadBundle(dir);
  } catch (const Error& e) {
    ErrorSite site = e.site();
    site.clip = clip;
    throw PermanentError(e.code(), e.message(), site);
  }
}

}  // namespace doasido::recon
