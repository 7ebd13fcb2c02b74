#include "recon/bundle_location.h"

#include "core/permanent_error.h"

namespace doasido::recon {

bool ListNamesBundle(const ClipContext& context) {
  const Json& meta = context.clip.metadata;
  return meta.is_object() && meta.contains("bundle") && meta["bundle"].is_string() &&
         !meta["bundle"].get<std::string>().empty();
}

std::filesystem::path BundleDir(const ClipContext& context) {
  if (ListNamesBundle(context)) {
    std::filesystem::path p = context.clip.metadata["bundle"].get<std::string>();
    if (p.is_relative() && !context.clip.source_list.empty()) {
      p = std::filesystem::path(context.clip.source_list).parent_path() / p;
    }
    return p;
  }
  return SiblingArtifactDir(context, kBundleStageName);
}

std::filesystem::path SiblingArtifactDir(const ClipContext& context, const std::string& stage) {
  // The output of the run the database records (ClipContext::inputs); a
  // context made by hand (tests, tools) has no inputs: the sibling folder.
  if (const auto it = context.inputs.find(stage); it != context.inputs.end()) return it->second;
  return context.artifact_dir.parent_path() / stage;
}

std::string ClipName(const ClipContext& context) {
  return context.clip.external_id.empty() ? std::to_string(context.clip.id)
                                          : context.clip.external_id;
}

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
