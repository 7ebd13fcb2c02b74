// Building shell commands from templates: quoting a value as one word and
// filling {placeholders}.
#pragma once

#include <string>

namespace doasido {

// `s` as one single-quoted /bin/sh word (embedded quotes escaped).
std::string ShellQuote(const std::string& s);

// Replaces every occurrence of `key` in `text` by `value` (left to right,
// never rescanning inserted text).
void ReplaceAll(std::string& text, const std::string& key, const std::string& value);

}  // namespace doasido
