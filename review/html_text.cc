// Escaping text for the pages: HTML content and JSON inside <script>.
#include "review/pages.h"

namespace doasido::review {

std::string ScriptJson(const Json& value) {
  const std::string dumped = value.dump();
  std::string out;
  out.reserve(dumped.size());
  for (char c : dumped) {
    if (c == '<') {
      out += "\\u003c";
    } else {
      out += c;
    }
  }
  return out;
}

namespace {

const char* kApiScript = R"js(
async function api(path, body) {
  const init = { headers: { 'X-Doasido-Token': cfg.token }, credentials: 'same-origin' };
  if (body !== undefined) {
    init.method = 'POST'; init.body = JSON.stringify(body);
    init.headers['Content-Type'] = 'application/json';
  }
  const res = await fetch(path, init);
  const data = await res.json().catch(() => ({}));
  if (!res.ok) throw new Error(data.error || res.statusText);
  return data;
}
)js";

}  // namespace

std::string ScriptedPage(const std::string& title, const std::string& nonce,
                         const std::string& style, const std::string& body, const Json& config,
                         const std::string& script) {
  return "<!doctype html>\n<html lang=\"en\"><head><meta charset=\"utf-8\">\n<title>" +
         HtmlEscape(title) + "</title>\n<style nonce=\"" + nonce + "\">" + style +
         "</style></head>\n<body>" + body + "<script type=\"application/json\" id=\"cfg\">" +
         ScriptJson(config) + "</script>\n<script nonce=\"" + nonce + "\">" + kApiScript +
         script + "</script>\n</body></html>\n";
}

}  // namespace doasido::review
