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

// `xml` with `prefix` put before every name it defines and every reference
// to one (bodies, joints, geoms, sites, tendons, actuators, sensors,
// equality and contact entries, assets, default classes), so that two
// models with the same names (a right hand and its mirror image) can be
// merged into one scene (AppendRootChildren). The top-level default, which
// has no name, becomes the class <prefix>main, given as childclass to the
// top-level bodies and as class to the actuators, tendons and other
// top-level elements that had no class. Throws Error("bad_mjcf") naming
// `label` for malformed XML.
std::string PrefixMjcfNames(const std::string& xml, const std::string& prefix, const std::string& label);

// Appends the children (comments left out) of the root element of `other`
// (parsed as ParseMjcfText with `label`) to `doc`'s root element.
void AppendRootChildren(tinyxml2::XMLDocument& doc, const std::string& other,
                        const std::string& label);

}  // namespace doasido::retarget
