#include "dataset/splits.h"

#include <algorithm>
#include <cmath>
#include <map>
#include <set>
#include <sstream>

#include "core/error.h"

namespace doasido::dataset {
namespace {

[[noreturn]] void Refuse(const std::string& part, const std::string& why) {
  throw Error("bad_option", "'" + part + "': " + why, {.field = "--split"});
}

// FNV-1a over the seed's bytes then the key: stable across platforms.
std::uint64_t OrderKey(std::int64_t seed, const std::string& key) {
  std::uint64_t h = 1469598103934665603ull;
  auto mix = [&h](unsigned char c) { h = (h ^ c) * 1099511628211ull; };
  for (int i = 0; i < 8; ++i) mix(static_cast<unsigned char>(static_cast<std::uint64_t>(seed) >> (8 * i)));
  for (unsigned char c : key) mix(c);
  return h;
}

}  // namespace

SplitFractions ParseSplits(const std::string& text) {
  SplitFractions out;
  std::set<std::string> names;
  std::stringstream in(text);
  std::string part;
  double sum = 0;
  while (std::getline(in, part, ',')) {
    const size_t eq = part.find('=');
    if (eq == std::string::npos) Refuse(part, "expected name=fraction");
    const std::string name = part.substr(0, eq);
    if (name.empty() || name.find_first_not_of("abcdefghijklmnopqrstuvwxyz0123456789_") !=
                            std::string::npos) {
      Refuse(part, "split names are lower-case letters, digits and _");
    }
    if (!names.insert(name).second) Refuse(part, "split named twice");
    double fraction = 0;
    size_t used = 0;
    try {
      fraction = std::stod(part.substr(eq + 1), &used);
    } catch (const std::exception&) {
      Refuse(part, "fraction is not a number");
    }
    if (used != part.size() - eq - 1 || !std::isfinite(fraction) || fraction < 0 || fraction > 1) {
      Refuse(part, "fraction must be a number in [0, 1]");
    }
    sum += fraction;
    out.emplace_back(name, fraction);
  }
  if (out.empty()) Refuse(text, "no splits given");
  if (std::abs(sum - 1) > 1e-6) Refuse(text, "fractions sum to " + std::to_string(sum) + ", not 1");
  return out;
}

void AssignSplits(std::vector<Episode>& episodes, const SplitFractions& fractions,
                  std::int64_t seed) {
  std::map<std::string, std::vector<Episode*>> by_video;
  for (Episode& e : episodes) by_video[e.video_key].push_back(&e);
  std::vector<std::pair<std::uint64_t, const std::string*>> order;
  for (const auto& [video, list] : by_video) order.emplace_back(OrderKey(seed, video), &video);
  std::sort(order.begin(), order.end(), [](const auto& a, const auto& b) {
    return a.first != b.first ? a.first < b.first : *a.second < *b.second;
  });
  std::vector<double> count(fractions.size(), 0);
  double placed = 0;
  for (const auto& [key, video] : order) {
    const auto& list = by_video[*video];
    placed += static_cast<double>(list.size());
    size_t best = 0;
    double best_deficit = -1e300;
    for (size_t s = 0; s < fractions.size(); ++s) {
      const double deficit = fractions[s].second * placed - count[s];
      if (fractions[s].second > 0 && deficit > best_deficit) {
        best = s;
        best_deficit = deficit;
      }
    }
    count[best] += static_cast<double>(list.size());
    for (Episode* e : list) e->split = fractions[best].first;
  }
}

}  // namespace doasido::dataset
