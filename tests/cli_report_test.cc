// `doasido report` end to end on a small synthetic pool run through the real
// filters: a self-contained page whose numbers equal `doasido status`, JSON
// and CSV that agree, thumbnails for rejected clips, and a clear note (not
// a failure) when a clip's video was deleted after analysis.
#include <gtest/gtest.h>

#include <fstream>

#include "core/config.h"
#include "db/database.h"
#include "tests/test_util.h"

namespace doasido {
namespace {

using testing::ReadCsv;
using testing::ReadFile;
using testing::RunDoasido;
using testing::TempDir;

size_t Count(const std::string& text, const std::string& what) {
  size_t n = 0;
  for (size_t at = text.find(what); at != std::string::npos; at = text.find(what, at + 1)) ++n;
  return n;
}

class CliReport : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    dir_ = new TempDir;
    const auto synth = RunDoasido(
        {"synth", "--out", (*dir_ / "synth").string(), "--clips", "8", "--seed", "1", "--frames",
         "30", "--width", "160", "--height", "120", "--mix",
         "clean=0.25,cut=0.125,fade=0.125,pan=0.125,out_of_frame=0.125,no_contact=0.125,"
         "static=0.125"});
    ASSERT_EQ(synth.exit_code, 0) << synth.err;
    db_ = (*dir_ / "work" / "d.db").string();
    ASSERT_EQ(RunDoasido({"init", "--db", db_, "--pipeline", "filters"}).exit_code, 0);
    const auto run = RunDoasido({"run", "--db", db_, (*dir_ / "synth").string(), "--jobs", "2"});
    ASSERT_EQ(run.exit_code, 0) << run.err;
  }
  static void TearDownTestSuite() { delete dir_; }
  static TempDir* dir_;
  static std::string db_;
};
TempDir* CliReport::dir_ = nullptr;
std::string CliReport::db_;

TEST_F(CliReport, PageIsSelfContainedAndAgreesWithStatus) {
  const auto out = *dir_ / "report";
  const auto r = RunDoasido({"report", "--db", db_, "--out", out.string()});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find("8 clips"), std::string::npos) << r.out;
  const std::string html = ReadFile(out / "report.html");
  EXPECT_NE(html.find("<svg id=\"funnel-chart\""), std::string::npos);
  EXPECT_NE(html.find("id=\"funnel-table\""), std::string::npos);
  EXPECT_EQ(html.find("<script"), std::string::npos);
  // Every src/href is inline. (Searched by hand: std::regex matches
  // recursively, and a data: URI of a thumbnail overflowed the stack under
  // AddressSanitizer.)
  for (const std::string attribute : {"src=\"", "href=\""}) {
    for (size_t at = html.find(attribute); at != std::string::npos;
         at = html.find(attribute, at + 1)) {
      const std::string target = html.substr(at + attribute.size(), 8);
      EXPECT_TRUE(target.rfind("data:", 0) == 0 || target.rfind("#", 0) == 0) << target;
    }
  }
  EXPECT_EQ(html.find("http://"), std::string::npos);
  EXPECT_EQ(html.find("https://"), std::string::npos);

  // The funnel equals `doasido status --json`, stage by stage.
  const auto status = RunDoasido({"status", "--db", db_, "--json"});
  ASSERT_EQ(status.exit_code, 0) << status.err;
  const Json s = Json::parse(status.out);
  const Json report = Json::parse(ReadFile(out / "report.json"));
  EXPECT_EQ(report["funnel"]["pool"], s["clips"]);
  std::map<std::string, std::map<std::string, std::int64_t>> cells;
  std::map<std::string, std::map<std::string, std::int64_t>> reasons;
  for (const auto& c : s["counts"]) {
    const std::string stage = c["stage"];
    const std::string state = c["state"];
    const std::string col = state == "done" ? c["verdict"].get<std::string>() : state;
    cells[stage][col] += c["count"].get<std::int64_t>();
    cells[stage]["entering"] += c["count"].get<std::int64_t>();
    if (state == "done" && c["verdict"] == "reject") {
      reasons[stage][c["reason"].get<std::string>()] += c["count"].get<std::int64_t>();
    }
  }
  std::int64_t rejected_total = 0;
  ASSERT_EQ(report["funnel"]["stages"].size(), s["pipeline"].size());
  for (const auto& st : report["funnel"]["stages"]) {
    auto& c = cells[st["stage"]];
    EXPECT_EQ(st["entering"], c["entering"]) << st["stage"];
    EXPECT_EQ(st["passed"], c["pass"]) << st["stage"];
    EXPECT_EQ(st["rejected"], c["reject"]) << st["stage"];
    EXPECT_EQ(st["flagged"], c["flag"]) << st["stage"];
    EXPECT_EQ(st["failed"], c["failed"]) << st["stage"];
    EXPECT_EQ(st["pending"], c["pending"] + c["running"]) << st["stage"];
    for (const auto& [reason, n] : reasons[st["stage"]]) {
      EXPECT_EQ(st["rejected_by_reason"][reason], n) << st["stage"] << " " << reason;
    }
    rejected_total += st["rejected"].get<std::int64_t>();
    // The page shows the same numbers in the stage's table row.
    const std::string row_start = "<tr data-stage=\"" + st["stage"].get<std::string>() +
                                  "\"><td class=\"l\">" + st["stage"].get<std::string>() +
                                  "</td><td>" + std::to_string(st["entering"].get<int>()) +
                                  "</td>";
    EXPECT_NE(html.find(row_start), std::string::npos) << row_start;
  }
  const std::string last = s["pipeline"].back();
  EXPECT_EQ(report["funnel"]["survivors"], cells[last]["pass"]);
  ASSERT_GT(rejected_total, 0) << "the defect mix must get some clips rejected";

  // Thumbnails: one image per rejected example, none missing.
  size_t images = 0;
  for (const auto& strip : report["thumbnails"]) {
    EXPECT_GT(strip["items"].size(), 0u);
    for (const auto& item : strip["items"]) {
      EXPECT_TRUE(item["image"].get<bool>()) << item["note"];
      images += item["image"].get<bool>();
    }
  }
  EXPECT_GT(images, 0u);
  EXPECT_EQ(Count(html, "class=\"thumb\""), images);
  EXPECT_EQ(Count(html, "src=\"data:image/jpeg;base64,"), images);
  EXPECT_GE(Count(html, "class=\"score-chart\""), 3u);

  // funnel.csv and report.json agree.
  const auto csv = ReadCsv(out / "funnel.csv");
  ASSERT_EQ(csv.size(), report["funnel"]["stages"].size() + 3);
  for (size_t k = 0; k < report["funnel"]["stages"].size(); ++k) {
    const auto& st = report["funnel"]["stages"][k];
    EXPECT_EQ(csv[k + 2][1], st["stage"].get<std::string>());
    EXPECT_EQ(std::stoll(csv[k + 2][2]), st["entering"].get<std::int64_t>());
    EXPECT_EQ(std::stoll(csv[k + 2][4]), st["rejected"].get<std::int64_t>());
  }
  EXPECT_EQ(std::stoll(csv.back()[2]), report["funnel"]["survivors"].get<std::int64_t>());
  const auto clips = ReadCsv(out / "clips.csv");
  EXPECT_EQ(clips.size(), 9u);
  for (const char* f : {"reasons.csv", "scores.csv", "histograms.csv", "sources.csv",
                        "stages.csv", "failures.csv"}) {
    EXPECT_TRUE(std::filesystem::exists(out / f)) << f;
  }
}

TEST_F(CliReport, DeletedVideoBecomesANote) {
  // The first rejected clip loses its video file after analysis.
  const auto first = *dir_ / "first";
  ASSERT_EQ(RunDoasido({"report", "--db", db_, "--out", first.string(), "--no-thumbnails"})
                .exit_code,
            0);
  EXPECT_EQ(ReadFile(first / "report.html").find("class=\"thumb\""), std::string::npos);
  std::string external;
  ClipId id = 0;
  for (const auto& row : ReadCsv(first / "clips.csv")) {
    if (row[3] == "rejected") {
      id = std::stoll(row[0]);
      external = row[1];
      break;
    }
  }
  ASSERT_NE(id, 0);
  std::string video;
  {
    Database db(db_);
    video = db.GetVideo(db.GetClip(id).video_id).path;
  }
  // Moved away and back, so the other test keeps its videos.
  ASSERT_TRUE(std::filesystem::exists(video));
  const std::string saved = video + ".saved";
  std::filesystem::rename(video, saved);
  const auto out = *dir_ / "report_missing";
  const auto r = RunDoasido({"report", "--db", db_, "--out", out.string(),
                             "--max-thumbnails", "1"});
  std::filesystem::rename(saved, video);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const std::string html = ReadFile(out / "report.html");
  const std::string note = "clip " + external + ": video file not found: " + video;
  EXPECT_NE(html.find(note), std::string::npos) << note;
  EXPECT_NE(r.out.find(note), std::string::npos) << r.out;
  const Json report = Json::parse(ReadFile(out / "report.json"));
  for (const auto& strip : report["thumbnails"]) EXPECT_LE(strip["items"].size(), 1u);
}

TEST(CliReportHelp, HelpHasAnExampleAndOutIsRequired) {
  const auto help = RunDoasido({"report", "--help"});
  EXPECT_EQ(help.exit_code, 0);
  EXPECT_NE(help.out.find("Example"), std::string::npos) << help.out;
  EXPECT_NE(help.out.find("--max-thumbnails"), std::string::npos);
  EXPECT_NE(help.out.find("--no-thumbnails"), std::string::npos);
  const auto top = RunDoasido({"--help"});
  EXPECT_NE(top.out.find("report"), std::string::npos);
  TempDir dir;
  const auto no_out = RunDoasido({"report", "--db", (dir / "d.db").string()});
  EXPECT_NE(no_out.exit_code, 0);
  EXPECT_NE((no_out.out + no_out.err).find("--out"), std::string::npos) << no_out.err;
  const auto missing =
      RunDoasido({"report", "--db", (dir / "typo.db").string(), "--out", (dir / "r").string()});
  EXPECT_NE(missing.exit_code, 0);
  EXPECT_NE(missing.err.find((dir / "typo.db").string()), std::string::npos) << missing.err;
  EXPECT_FALSE(std::filesystem::exists(dir / "typo.db"));
}

}  // namespace
}  // namespace doasido
