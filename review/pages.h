// The web app's pages: HTML with inline CSS and JS (no external assets),
// each script and style tag carrying the response's CSP nonce. Page data
// goes in as JSON inside <script type="application/json" id="cfg">.
#pragma once

#include <string>

#include "core/config.h"
#include "review/study.h"

namespace doasido::review {

// Escapes text for HTML element content and attribute values.
std::string HtmlEscape(const std::string& text);
// JSON safe to place inside a <script> element ("<" written as \u003c).
std::string ScriptJson(const Json& value);

// The flagged-clip queue page; `config` holds token and reviewer.
std::string ReviewPage(const std::string& nonce, const Json& config);
// One rater's trials of a study; `config` holds token, study and rater.
std::string StudyPage(const std::string& nonce, const Json& config);
// The study's results, rendered on the server (no script).
std::string StudySummaryPage(const std::string& nonce, const StudySummary& summary);

}  // namespace doasido::review
