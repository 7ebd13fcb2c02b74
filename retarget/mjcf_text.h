// MJCF as text: parsing with a named error, printing, and merging one
// document's top-level elements into another (hand + scene, arm + hand).
#pragma once

#include <string>

#include <tinyxml2.h>

namespace doasido::retarget {

// Parses `xml` into `doc`; throws Error("bad_mjcf") naming `label` as the
// file when it is not well-formed XML.
void ParseMjcfText(const std::string& xml, const std::string& label, tinyxml2::XMLDocument& doc);

// The document as text.
std::string PrintMjcf(const tinyxml2::XMLDocument& doc);

// Appends the children (comments left out) of the root element of `other`
// (parsed as ParseMjcfText with `label`) to `doc`'s root element.
void AppendRootChildren(tinyxml2::XMLDocument& doc, const std::string& other,
                        const std::string& label);

}  // namespace doasido::retarget
