#include "recon/bundle/bundle_location.h"

#include "core/error.h"
#include "core/error_codes.h"

namespace doasido::recon {

ClipBundle ReadClipBundle(const std::filesystem::path& dir, const std::string& clip) {
  try {
    return ReadBundle(dir);
  } catch (const Error& e) {
    // The same files fail again on a retry: a bundle that does not read is
    // kBadBundle (permanent), its reader's own code kept in the message.
    ErrorSite site = e.site();
    site.clip = clip;
    if (IsPermanentError(e.code())) throw Error(e.code(), e.message(), site);
    throw Error(kBadBundle, e.code() + ": " + e.message(), site);
  }
}

}  // namespace doasido::recon
