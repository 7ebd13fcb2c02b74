#include "core/error.h"

namespace doasido {

std::string FormatWithSite(const std::string& message, const ErrorSite& site) {
  std::string where;
  auto add = [&where](const std::string& part) {
    where += where.empty() ? "" : ", ";
    where += part;
  };
  if (!site.clip.empty()) add("clip " + site.clip);
  if (!site.file.empty()) {
    add("file " + site.file + (site.line > 0 ? ":" + std::to_string(site.line) : ""));
  }
  if (!site.field.empty()) add("field " + site.field);
  return where.empty() ? message : message + " [" + where + "]";
}

Error::Error(std::string code, std::string message, ErrorSite site)
    : std::runtime_error(code + ": " + FormatWithSite(message, site)),
      code_(std::move(code)),
      message_(std::move(message)),
      site_(std::move(site)) {}

}  // namespace doasido
