// Errors that name what went wrong and where: the clip, the file and the
// field. Every user-facing failure in doasido is one of these, so the CLI and
// the queue can print and store a message a person can act on.
#pragma once

#include <stdexcept>
#include <string>

namespace doasido {

// Where an error happened. Empty parts are left out of the message.
struct ErrorSite {
  std::string clip;   // clip id or external id
  std::string file;   // path of the file being read or written
  long line = 0;      // 1-based line in `file`, 0 when not line-oriented
  std::string field;  // column, key or attribute name
};

// An error with a short machine-readable code ("video_truncated",
// "bad_timestamp", ...) and a human message. what() gives
// "code: message [clip C, file F:L, field X]".
class Error : public std::runtime_error {
 public:
  Error(std::string code, std::string message, ErrorSite site = {});

  const std::string& code() const { return code_; }
  const std::string& message() const { return message_; }
  const ErrorSite& site() const { return site_; }

 private:
  std::string code_;
  std::string message_;
  ErrorSite site_;
};

// Formats "message [clip C, file F:L, field X]".
std::string FormatWithSite(const std::string& message, const ErrorSite& site);

}  // namespace doasido
