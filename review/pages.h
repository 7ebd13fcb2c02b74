// The web app's pages: HTML with inline CSS and JS (no external assets),
// each script and style tag carrying the response's CSP nonce. Page data
// goes in as JSON inside <script type="application/json" id="cfg">.
#pragma once

#include <string>
#include <vector>

#include "core/config.h"
#include "core/html_escape.h"
#include "review/server.h"
#include "review/study.h"

namespace doasido::review {

// JSON safe to place inside a <script> element ("<" written as \u003c).
std::string ScriptJson(const Json& value);
// A page with one style and one script element (both carrying `nonce`),
// `config` as JSON in <script type="application/json" id="cfg">, and before
// `script` the shared helpers: `api(path, body)` fetches JSON (POST when
// `body` is given) with the page's token from cfg.token and throws the
// server's error text on a non-2xx answer.
std::string ScriptedPage(const std::string& title, const std::string& nonce,
                         const std::string& style, const std::string& body, const Json& config,
                         const std::string& script);

// The style both decision pages (review, verify) start from: dark theme,
// header bar, form controls, accept and reject buttons.
extern const char* const kDecisionPageStyle;

// Reasons only a reviewer gives (no stage does): the flag was wrong, the
// video is poor, something else.
inline constexpr const char* kReasonFalseFlag = "false_flag";
inline constexpr const char* kReasonPoorQuality = "poor_quality";
inline constexpr const char* kReasonOther = "other";
std::vector<ReasonChoice> ReviewOnlyReasons();

// The flagged-clip queue page; `config` holds token, reviewer and
// reason_for_stage (stage -> default reason code). Its reason list is
// `stage_reasons` then ReviewOnlyReasons(), in that order.
std::string ReviewPage(const std::string& nonce, const Json& config,
                       const std::vector<ReasonChoice>& stage_reasons);
// One rater's trials of a study; `config` holds token, study and rater.
std::string StudyPage(const std::string& nonce, const Json& config);
// The study's results, rendered on the server (no script).
std::string StudySummaryPage(const std::string& nonce, const StudySummary& summary);

}  // namespace doasido::review
