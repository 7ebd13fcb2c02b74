// Clip-list readers against the real EPIC-KITCHENS and 100DOH lists and a
// list with every kind of bad row we know of.
#include <gtest/gtest.h>

#include <fstream>
#include <map>
#include <set>

#include "db/database.h"
#include "ingest/clip_list.h"
#include "pipeline/ingest.h"
#include "tests/test_util.h"

namespace doasido::ingest {
namespace {

using doasido::pipeline::IngestList;
using doasido::testing::SharedData;
using doasido::testing::TempDir;
using doasido::testing::WriteFile;

TEST(IngestLists, EpicValidationListIngestsEveryRowWithItsFrames) {
  const auto list = SharedData() / "lists" / "EPIC_100_validation.csv";
  // Expected spans, read independently: the first eight columns never hold
  // quoted commas, so a plain split is exact for them.
  std::map<std::string, std::pair<long, long>> expected;
  std::ifstream in(list);
  std::string line;
  std::getline(in, line);
  while (std::getline(in, line)) {
    std::vector<std::string> f;
    size_t pos = 0;
    for (int i = 0; i < 8; ++i) {
      const size_t next = line.find(',', pos);
      f.push_back(line.substr(pos, next - pos));
      pos = next + 1;
    }
    expected[f[0]] = {std::stol(f[6]), std::stol(f[7])};
  }
  ASSERT_EQ(expected.size(), 9668u);

  TempDir dir;
  Database db(dir / "epic.db");
  db.SetPipeline({"probe"});
  const auto summary = IngestList(db, list);
  EXPECT_EQ(summary.format, "epic");
  EXPECT_TRUE(summary.errors.empty()) << summary.errors.front().Format();
  EXPECT_EQ(summary.inserted, static_cast<std::int64_t>(expected.size()));
  EXPECT_EQ(db.CountClips(), static_cast<std::int64_t>(expected.size()));

  std::set<std::string> seen;
  for (ClipId id = 1; id <= db.CountClips(); ++id) {
    const auto clip = db.GetClip(id);
    const auto it = expected.find(clip.external_id);
    ASSERT_NE(it, expected.end()) << clip.external_id;
    EXPECT_EQ(clip.start_frame, it->second.first) << clip.external_id;
    EXPECT_EQ(clip.end_frame, it->second.second) << clip.external_id;
    ASSERT_TRUE(clip.start_s && clip.end_s);
    // EPIC's frame numbers are timestamps x 60 (rounded), not frame indices
    // at the video's own rate; ingest says so in the metadata.
    EXPECT_EQ(clip.metadata.at("frame_numbers_fps"), 60);
    EXPECT_NEAR(*clip.start_s * 60, static_cast<double>(*clip.start_frame), 1.0)
        << clip.external_id;
    EXPECT_NEAR(*clip.end_s * 60, static_cast<double>(*clip.end_frame), 1.0)
        << clip.external_id;
    seen.insert(clip.external_id);
  }
  EXPECT_EQ(seen.size(), expected.size());
  // Re-ingesting is a no-op.
  const auto again = IngestList(db, list);
  EXPECT_EQ(again.inserted, 0);
  EXPECT_EQ(again.already_present, static_cast<std::int64_t>(expected.size()));
}

TEST(IngestLists, BadRowsAreNamedAndGoodRowsIngested) {
  TempDir dir;
  const std::string cups = (SharedData() / "videos" / "02_cups.mp4").string();
  const std::string blocks = (SharedData() / "videos" / "03_blocks.mp4").string();
  std::string text =
      "video,id,start,end,source,note\n"                                  // line 1
      + cups + ",good1,0,99,internet,plain\n"                             // 2 good
      + blocks + ",good2,00:00:01.5,00:00:04,egocentric,\"a, b, c\"\n"    // 3 good, quoted commas
      + cups + ",missing_column,0,10,internet\n"                          // 4 missing column
      + cups + ",bad_time,12:7x:00,00:00:20,internet,x\n"                 // 5 bad timestamp
      + cups + ",backwards,50,10,internet,x\n"                            // 6 end before start
      + cups + ",negative,-5,10,internet,x\n"                             // 7 negative
      + cups + ",huge,0,99999999999999,internet,x\n"                      // 8 huge
      + "/no/such/video.mp4,missing_file,0,10,internet,x\n"               // 9 missing file
      + cups + ",dup,0,99,internet,again\n"                               // 10 duplicate of 2
      + "\n"                                                              // 11 empty line
      + cups + ",unterminated,0,20,internet,\"open quote\n";              // 12 (runs to EOF)
  // Non-UTF-8 bytes and NaN go before the unterminated quote.
  const std::string tail = cups + ",latin1,0,30,internet,caf\xE9\n"  // 12 not UTF-8
                           + cups + ",nan,NaN,10,internet,x\n"        // 13 NaN
                           + cups + ",good3,100,199,generated,ok\n"   // 14 good
                           + cups + ",unterminated,0,20,internet,\"open quote\n";  // 15
  text = text.substr(0, text.rfind(cups + ",unterminated")) + tail;
  WriteFile(dir / "clips.csv", text);

  Database db(dir / "bad.db");
  db.SetPipeline({"probe"});
  const auto summary = IngestList(db, dir / "clips.csv");
  EXPECT_EQ(summary.inserted, 3);
  std::map<long, std::string> bad;  // line -> "field: reason"
  for (const auto& e : summary.errors) {
    EXPECT_EQ(e.file, (dir / "clips.csv").string());
    bad[e.line] = e.field + ": " + e.reason;
  }
  auto expect_bad = [&bad](long line, const std::string& field, const std::string& words) {
    const auto it = bad.find(line);
    ASSERT_NE(it, bad.end()) << "line " << line << " not reported";
    EXPECT_EQ(it->second.rfind(field, 0), 0u) << it->second;
    EXPECT_NE(it->second.find(words), std::string::npos) << it->second;
  };
  expect_bad(4, "note", "expected 6 columns, found 5");
  expect_bad(5, "start", "not a time");
  expect_bad(6, "end_frame", "before start");
  expect_bad(7, "start", "negative");
  expect_bad(8, "end", "out of range");
  expect_bad(9, "video", "file not found");
  expect_bad(10, "video", "duplicate of line 2");
  expect_bad(11, "", "empty line");
  expect_bad(12, "", "UTF-8");
  expect_bad(13, "start", "not a time");
  expect_bad(15, "", "unterminated");
  EXPECT_EQ(bad.size(), 11u);

  // The row with quoted commas kept its metadata whole and its time span.
  for (ClipId id = 1; id <= 3; ++id) {
    const auto clip = db.GetClip(id);
    if (clip.external_id != "good2") continue;
    EXPECT_EQ(clip.metadata.at("note"), "a, b, c");
    EXPECT_EQ(clip.metadata.at("source"), "egocentric");
    EXPECT_DOUBLE_EQ(*clip.start_s, 1.5);
    EXPECT_DOUBLE_EQ(*clip.end_s, 4.0);
  }
}

TEST(IngestLists, MalformedListAsAWholeIsAClearError) {
  TempDir dir;
  WriteFile(dir / "nocol.csv", "name,start\nx,1\n");
  try {
    ReadClipList(dir / "nocol.csv");
    FAIL();
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("no video column"), std::string::npos);
    EXPECT_NE(std::string(e.what()).find("nocol.csv"), std::string::npos);
  }
  EXPECT_THROW(ReadClipList(dir / "absent.csv"), Error);
}

TEST(IngestLists, JsonLinesAndTsv) {
  TempDir dir;
  const std::string cups = (SharedData() / "videos" / "02_cups.mp4").string();
  WriteFile(dir / "l.jsonl", "{\"video\": \"" + cups +
                                 "\", \"start_frame\": 3, \"end_frame\": 9, \"tags\": [1, 2]}\n"
                                 "not json\n"
                                 "{\"video\": \"" + cups + "\", \"start_time\": \"1:02.5\"}\n");
  auto r = ReadClipList(dir / "l.jsonl");
  ASSERT_EQ(r.rows.size(), 2u);
  EXPECT_EQ(r.rows[0].clip.start_frame, 3);
  EXPECT_EQ(r.rows[0].clip.metadata.at("tags"), Json({1, 2}));
  EXPECT_DOUBLE_EQ(*r.rows[1].clip.start_s, 62.5);
  ASSERT_EQ(r.errors.size(), 1u);
  EXPECT_EQ(r.errors[0].line, 2);

  WriteFile(dir / "l.tsv", "path\tstart_frame\tend_frame\n" + cups + "\t0\t5\n");
  r = ReadClipList(dir / "l.tsv");
  ASSERT_EQ(r.rows.size(), 1u);
  EXPECT_EQ(r.rows[0].clip.end_frame, 5);
}

TEST(IngestLists, Timestamps) {
  EXPECT_DOUBLE_EQ(*ParseTimestamp("00:00:01.89"), 1.89);
  EXPECT_DOUBLE_EQ(*ParseTimestamp("01:02:03.5"), 3723.5);
  EXPECT_DOUBLE_EQ(*ParseTimestamp("2:30"), 150.0);
  EXPECT_DOUBLE_EQ(*ParseTimestamp("12.25"), 12.25);
  for (const char* bad : {"", "abc", "1:60", "-3", "nan", "inf", "1::2", "1:2:3:4"}) {
    EXPECT_FALSE(ParseTimestamp(bad)) << bad;
  }
}

TEST(IngestLists, HundredDohFrameNames) {
  auto a = ParseFrameName("boardgame_v_-4f2LC_xhs2k_frame000031");
  ASSERT_TRUE(a);
  EXPECT_EQ(a->genre, "boardgame");
  EXPECT_EQ(a->video, "-4f2LC_xhs2k");
  EXPECT_EQ(a->frame, 31);
  auto b = ParseFrameName("EK_test_P24-09_0000062539");
  ASSERT_TRUE(b);
  EXPECT_EQ(b->genre, "EK");
  EXPECT_EQ(b->split, "test");
  EXPECT_EQ(b->video, "P24-09");
  EXPECT_EQ(b->frame, 62539);
  EXPECT_FALSE(ParseFrameName("nonsense"));

  // Every name of the real list parses; frames group into one clip per video.
  const auto list = SharedData() / "lists" / "100doh_ego_test_framenames.txt";
  std::ifstream in(list);
  std::string name;
  std::set<std::string> videos;
  long names = 0;
  while (std::getline(in, name)) {
    if (name.empty()) continue;
    const auto parsed = ParseFrameName(name);
    ASSERT_TRUE(parsed) << name;
    videos.insert(parsed->genre + "_" + parsed->video);
    ++names;
  }
  const auto r = ReadClipList(list);
  EXPECT_EQ(r.format, "framenames");
  EXPECT_TRUE(r.errors.empty());
  EXPECT_EQ(r.rows.size(), videos.size());
  EXPECT_GT(names, 10000);
}

TEST(IngestLists, VocFolderBecomesClipsWithDetections) {
  TempDir dir;
  auto xml = [](int xmin, int state, int side) {
    return "<annotation><filename>x.jpg</filename><size><width>640</width><height>480</height>"
           "</size><object><name>hand</name><bndbox><xmin>" + std::to_string(xmin) +
           "</xmin><ymin>11</ymin><xmax>60</xmax><ymax>80</ymax></bndbox><contactstate>" +
           std::to_string(state) + "</contactstate><handside>" + std::to_string(side) +
           "</handside><unitdx>0.6</unitdx><unitdy>0.8</unitdy><magnitude>50</magnitude>"
           "<objxmin>None</objxmin></object><object><name>targetobject</name><bndbox>"
           "<xmin>100</xmin><ymin>100</ymin><xmax>150</xmax><ymax>140</ymax></bndbox>"
           "<contactleft>0</contactleft><contactright>1</contactright></object></annotation>";
  };
  WriteFile(dir / "voc" / "Annotations" / "kitchen_v_ab_c_frame000010.xml", xml(21, 3, 1));
  WriteFile(dir / "voc" / "Annotations" / "kitchen_v_ab_c_frame000020.xml", xml(31, 0, 0));
  WriteFile(dir / "voc" / "Annotations" / "kitchen_v_zz_frame000005.xml", xml(1, 4, 1));
  WriteFile(dir / "voc" / "Annotations" / "kitchen_v_zz_frame000006.xml", "<annotation><object>");
  const auto r = ReadClipList(dir / "voc");
  EXPECT_EQ(r.format, "voc");
  ASSERT_EQ(r.rows.size(), 2u);
  ASSERT_EQ(r.errors.size(), 1u);
  EXPECT_NE(r.errors[0].file.find("frame000006.xml"), std::string::npos);
  const auto& ab = r.rows[0].clip.external_id == "kitchen_v_ab_c" ? r.rows[0] : r.rows[1];
  EXPECT_EQ(ab.clip.start_frame, 10);
  EXPECT_EQ(ab.clip.end_frame, 20);
  EXPECT_EQ(ab.video, (dir / "voc" / "videos" / "ab_c.mp4").string());
  ASSERT_EQ(ab.detections.size(), 4u);
  const auto& hand = ab.detections[0];
  EXPECT_EQ(hand.kind, "hand");
  EXPECT_DOUBLE_EQ(hand.x1, 20);  // 1-based inclusive -> 0-based
  EXPECT_DOUBLE_EQ(hand.x2, 60);
  EXPECT_EQ(hand.contact_state, 3);
  EXPECT_EQ(hand.hand_side, 1);
  EXPECT_DOUBLE_EQ(hand.dy, 0.8);
  EXPECT_EQ(ab.detections[1].kind, "object");

  // The same folder named relative to the working directory finds the same
  // videos.
  const auto cwd = std::filesystem::current_path();
  std::filesystem::current_path(dir.path());
  const auto relative = ReadClipList("voc");
  std::filesystem::current_path(cwd);
  ASSERT_EQ(relative.rows.size(), 2u);
  EXPECT_EQ(relative.rows[0].video, r.rows[0].video);
}

}  // namespace
}  // namespace doasido::ingest
