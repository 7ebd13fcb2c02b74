#include "robot/mjcf_text.h"

#include <filesystem>

#include "core/error.h"

namespace doasido::retarget {

void ParseMjcfText(const std::string& xml, const std::string& label, tinyxml2::XMLDocument& doc) {
  if (doc.Parse(xml.c_str()) != tinyxml2::XML_SUCCESS) {
    throw Error("bad_mjcf", std::string("malformed XML: ") + doc.ErrorStr(), {.file = label});
  }
}

std::string PrintMjcf(const tinyxml2::XMLDocument& doc) {
  tinyxml2::XMLPrinter printer;
  doc.Print(&printer);
  return printer.CStr();
}

namespace {

// Attributes that hold a name defined elsewhere in the model.
constexpr const char* kReferences[] = {
    "class", "childclass", "mesh", "material", "texture", "hfield", "skin", "joint", "jointinparent",
    "body", "geom", "site", "tendon", "actuator", "objname", "refname", "refsite", "cranksite",
    "slidersite", "sidesite", "target", "body1", "body2", "geom1", "geom2", "joint1", "joint2",
    "tendon1", "tendon2", "site1", "site2"};

void PrefixTree(tinyxml2::XMLElement* e, const std::string& prefix) {
  for (tinyxml2::XMLElement* c = e->FirstChildElement(); c; c = c->NextSiblingElement()) {
    // An asset without a name is named by its file's stem; references use that name.
    const std::string tag = c->Name();
    const bool asset = tag == "mesh" || tag == "texture" || tag == "hfield" || tag == "skin";
    if (asset && !c->Attribute("name") && c->Attribute("file")) {
      c->SetAttribute("name", std::filesystem::path(c->Attribute("file")).stem().string().c_str());
    }
    if (const char* name = c->Attribute("name")) c->SetAttribute("name", (prefix + name).c_str());
    for (const char* attribute : kReferences) {
      if (const char* value = c->Attribute(attribute)) c->SetAttribute(attribute, (prefix + value).c_str());
    }
    PrefixTree(c, prefix);
  }
}

}  // namespace

std::string PrefixMjcfNames(const std::string& xml, const std::string& prefix, const std::string& label) {
  tinyxml2::XMLDocument doc;
  ParseMjcfText(xml, label, doc);
  tinyxml2::XMLElement* root = doc.RootElement();
  PrefixTree(root, prefix);
  // The unnamed top-level default becomes a class of its own.
  const std::string main = prefix + "main";
  tinyxml2::XMLElement* defaults = root->FirstChildElement("default");
  if (!defaults) return PrintMjcf(doc);
  tinyxml2::XMLElement* wrapper = doc.NewElement("default");
  while (tinyxml2::XMLNode* child = defaults->FirstChild()) wrapper->InsertEndChild(child);
  wrapper->SetAttribute("class", main.c_str());
  defaults->InsertEndChild(wrapper);
  // Sections whose elements take a class (sensors and contact exclusions do not).
  for (tinyxml2::XMLElement* section = root->FirstChildElement(); section; section = section->NextSiblingElement()) {
    const std::string tag = section->Name();
    for (tinyxml2::XMLElement* e = section->FirstChildElement(); e; e = e->NextSiblingElement()) {
      const std::string child = e->Name();
      const char* attribute = tag == "worldbody" && child == "body" ? "childclass"
                              : tag == "actuator" || tag == "tendon" || tag == "equality" ||
                                        (tag == "contact" && child == "pair")
                                  ? "class"
                                  : nullptr;
      if (attribute && !e->Attribute(attribute)) e->SetAttribute(attribute, main.c_str());
    }
  }
  return PrintMjcf(doc);
}

void AppendRootChildren(tinyxml2::XMLDocument& doc, const std::string& other,
                        const std::string& label) {
  tinyxml2::XMLDocument parsed;
  ParseMjcfText(other, label, parsed);
  for (const tinyxml2::XMLNode* n = parsed.RootElement()->FirstChild(); n; n = n->NextSibling()) {
    if (!n->ToComment()) doc.RootElement()->InsertEndChild(n->DeepClone(&doc));
  }
}

}  // namespace doasido::retarget
