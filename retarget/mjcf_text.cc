#include "retarget/mjcf_text.h"

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

void AppendRootChildren(tinyxml2::XMLDocument& doc, const std::string& other,
                        const std::string& label) {
  tinyxml2::XMLDocument parsed;
  ParseMjcfText(other, label, parsed);
  for (const tinyxml2::XMLNode* n = parsed.RootElement()->FirstChild(); n; n = n->NextSibling()) {
    if (!n->ToComment()) doc.RootElement()->InsertEndChild(n->DeepClone(&doc));
  }
}

}  // namespace doasido::retarget
