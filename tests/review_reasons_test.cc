// The review page's reason list against the reason codes the stages can
// give: read from the sources (every kReason* constant of the domain and
// stage folders), not from the registry the page is built from, so a
// reason a stage gives but the registry does not list, or a renamed one,
// fails here.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <map>
#include <regex>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include "review/pages.h"
#include "stages/stage_registry.h"

namespace doasido::review {
namespace {

namespace fs = std::filesystem;

// The folders whose code gives verdicts: the domain folders and stages/.
const char* const kVerdictFolders[] = {"video", "ingest",   "filters", "hands",
                                       "recon", "retarget", "robot",   "stages"};

std::string ReadAll(const fs::path& file) {
  std::ifstream in(file);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

// Every source file of the verdict folders with extension `ext`.
std::vector<fs::path> Sources(const std::string& ext) {
  std::vector<fs::path> out;
  for (const char* folder : kVerdictFolders) {
    for (const auto& e : fs::recursive_directory_iterator(fs::path(DOASIDO_SOURCE_DIR) / folder)) {
      if (e.is_regular_file() && e.path().extension() == ext) out.push_back(e.path());
    }
  }
  return out;
}

std::set<std::string> DeclaredReasonCodes() {
  const std::regex constant(R"re(kReason\w+\s*=\s*"([^"]+)")re");
  std::set<std::string> codes;
  for (const auto& file : Sources(".h")) {
    const std::string text = ReadAll(file);
    for (std::sregex_iterator it(text.begin(), text.end(), constant), end; it != end; ++it) {
      codes.insert((*it)[1]);
    }
  }
  return codes;
}

std::vector<std::string> PageReasonCodes() {
  std::vector<ReasonChoice> stage_reasons;
  for (const auto& r : stages::StageReasons()) stage_reasons.push_back({r.code, r.label});
  const std::string page = ReviewPage("n0nce", {{"token", "t"}}, stage_reasons);
  const std::regex option(R"re(<option value="([^"]*)">)re");
  std::vector<std::string> codes;
  for (std::sregex_iterator it(page.begin(), page.end(), option), end; it != end; ++it) {
    if (!(*it)[1].str().empty()) codes.push_back((*it)[1]);  // "" is the "— reason —" prompt
  }
  return codes;
}

TEST(ReviewReasons, EveryReasonAStageGivesIsAConstantOfItsHeader) {
  // A literal reason in a stage's code would escape the list below.
  const std::regex literal(R"re((\.reason\s*=\s*"|SetVerdict\([^;]*Verdict::k\w+,\s*"))re");
  for (const auto& file : Sources(".cc")) {
    const std::string text = ReadAll(file);
    EXPECT_FALSE(std::regex_search(text, literal))
        << file << " gives a reason code as a string literal: name it kReason* in its header";
  }
}

TEST(ReviewReasons, ThePageListsEveryStageReasonAndNothingElse) {
  const std::set<std::string> declared = DeclaredReasonCodes();
  ASSERT_GE(declared.size(), 18u) << "the scan found too few kReason* constants";
  std::set<std::string> expected = declared;
  for (const auto& r : ReviewOnlyReasons()) expected.insert(r.code);

  const std::vector<std::string> page = PageReasonCodes();
  const std::set<std::string> listed(page.begin(), page.end());
  EXPECT_EQ(listed.size(), page.size()) << "a reason is listed twice";
  for (const auto& code : expected) {
    EXPECT_TRUE(listed.count(code)) << "reason '" << code << "' is missing from the page";
  }
  for (const auto& code : listed) {
    EXPECT_TRUE(expected.count(code)) << "the page lists '" << code << "', which no stage gives";
  }
  // The registry lists only declared codes, each with words for a person.
  for (const auto& entry : stages::StageTable()) {
    for (const auto& r : entry.reasons) {
      EXPECT_TRUE(declared.count(r.code)) << entry.name << " lists undeclared '" << r.code << "'";
      EXPECT_FALSE(r.label.empty()) << entry.name << ": '" << r.code << "' has no label";
    }
  }
}

TEST(ReviewReasons, TheFiltersReasonsComeFirstForTheNumberKeys) {
  const std::vector<std::string> page = PageReasonCodes();
  ASSERT_GE(page.size(), 9u);
  const std::set<std::string> first(page.begin(), page.begin() + 9);  // keys 1-9
  for (const char* code : {"shot_boundary", "no_interaction", "out_of_frame", "no_activity",
                           "camera_motion", "no_detections"}) {
    EXPECT_TRUE(first.count(code)) << code << " is not among the first nine";
  }
}

TEST(ReviewReasons, ARejectionOfAFlaggedClipTakesItsFilterRejectReason) {
  // The map the page held by hand before it came from the registry.
  const std::map<std::string, std::string> expected = {{"interaction", "no_interaction"},
                                                       {"out_of_frame", "out_of_frame"},
                                                       {"shot_boundary", "shot_boundary"},
                                                       {"activity", "no_activity"},
                                                       {"camera_motion", "camera_motion"}};
  EXPECT_EQ(stages::ReviewDefaultReasons(), expected);
}

}  // namespace
}  // namespace doasido::review
