#include "ingest/object_prompt.h"

#include <cmath>
#include <sstream>

#include "ingest/list_rows.h"

namespace doasido::ingest {
namespace {

constexpr const char* kForm = "FRAME:X,Y,W,H[:CATEGORY]";

// One "FRAME:X,Y,W,H[:CATEGORY]"; "" or what is wrong.
std::string ParseOne(const std::string& text, ObjectPrompt* p) {
  const auto colon = text.find(':');
  if (colon == std::string::npos) return "'" + text + "' is not " + kForm;
  const auto frame = rows::ParseInt(rows::Trim(text.substr(0, colon)));
  if (!frame || *frame < 0 || *frame > rows::kMaxFrame) {
    return "'" + text + "': the frame must be a whole number >= 0";
  }
  std::string box = text.substr(colon + 1);
  const auto second = box.find(':');
  if (second != std::string::npos) {
    p->category = rows::Trim(box.substr(second + 1));
    box = box.substr(0, second);
    if (p->category.empty()) return "'" + text + "': empty category after the box";
  }
  std::vector<double> v;
  std::stringstream cells(box);
  for (std::string cell; std::getline(cells, cell, ',');) {
    const auto number = rows::ParseReal(rows::Trim(cell));
    if (!number) return "'" + text + "': '" + cell + "' is not a number (" + kForm + ")";
    v.push_back(*number);
  }
  if (v.size() != 4) return "'" + text + "': the box needs 4 numbers X,Y,W,H (" + kForm + ")";
  if (!(v[2] > 0 && v[3] > 0)) return "'" + text + "': the box's W and H must be > 0";
  p->frame = *frame;
  p->x = v[0], p->y = v[1], p->w = v[2], p->h = v[3];
  return "";
}

}  // namespace

std::string ParseObjectPrompts(const std::string& text, std::vector<ObjectPrompt>* out) {
  out->clear();
  std::stringstream parts(text);
  for (std::string part; std::getline(parts, part, ';');) {
    part = rows::Trim(part);
    if (part.empty()) continue;
    ObjectPrompt p;
    if (std::string why = ParseOne(part, &p); !why.empty()) return why;
    out->push_back(std::move(p));
  }
  if (out->empty()) return "no box (" + std::string(kForm) + ")";
  return "";
}

}  // namespace doasido::ingest
