// Escaping text for HTML and SVG (XML) pages written by the project.
#pragma once

#include <string>

namespace doasido {

// `text` with &, <, >, " and ' replaced by entities: safe as element content
// and inside quoted attribute values of HTML and XML.
std::string HtmlEscape(const std::string& text);

}  // namespace doasido
