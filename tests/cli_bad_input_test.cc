// Bad input never crashes, hangs or passes silently (issue 13): each input
// below gets its named error and exit code, the other rows and clips of the
// same batch are unharmed (checked in the database), and errors a retry
// cannot fix fail at the first attempt.
#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <sys/stat.h>

#include <chrono>
#include <map>
#include <string>

#include "db/database.h"
#include "tests/test_util.h"

namespace doasido {
namespace {

namespace fs = std::filesystem;
using ::testing::HasSubstr;
using testing::RunDoasido;
using testing::SharedData;
using testing::ShellOk;
using testing::TempDir;
using testing::WriteFile;

// Every run by the clip's external id.
std::map<std::string, StageRunRow> RunsById(const fs::path& db) {
  Database d(db, Database::OpenMode::kExisting);
  std::map<std::string, StageRunRow> out;
  for (const auto& r : d.ListRuns({})) out[r.external_id] = r;
  return out;
}

// Runs `doasido worker --until-empty` and returns its wall time in seconds.
double RunWorker(const fs::path& db, const std::vector<std::string>& extra = {}) {
  std::vector<std::string> args = {"worker", "--db", db.string(), "--until-empty", "--poll", "0.1"};
  args.insert(args.end(), extra.begin(), extra.end());
  const auto start = std::chrono::steady_clock::now();
  const auto r = RunDoasido(args);
  EXPECT_EQ(r.exit_code, 0) << r.err;
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

void Queue(const fs::path& db, const std::string& pipeline, const fs::path& list) {
  ASSERT_EQ(RunDoasido({"init", "--db", db.string(), "--pipeline", pipeline}).exit_code, 0);
  const auto r = RunDoasido({"ingest", "--db", db.string(), list.string()});
  ASSERT_EQ(r.exit_code, 0) << r.err;
}

std::string Cups() { return (SharedData() / "videos" / "02_cups.mp4").string(); }

TEST(BadInput, AFifoIsRefusedAtProbeWithoutBeingOpened) {
  TempDir dir;
  ASSERT_EQ(mkfifo((dir / "pipe.mp4").c_str(), 0644), 0);
  WriteFile(dir / "l.csv", "video,id,start_frame,end_frame\npipe.mp4,pipe,0,29\n" + Cups() +
                               ",cups,0,29\n");
  Queue(dir / "d.db", "probe", dir / "l.csv");
  RunWorker(dir / "d.db");
  auto runs = RunsById(dir / "d.db");
  EXPECT_EQ(runs["pipe"].state, RunState::kFailed);
  EXPECT_EQ(runs["pipe"].attempts, 1);
  EXPECT_THAT(runs["pipe"].error, HasSubstr("not_a_regular_file"));
  EXPECT_THAT(runs["pipe"].error, HasSubstr("FIFO"));
  EXPECT_EQ(runs["cups"].state, RunState::kDone);
}

// A stage that opens the FIFO itself (no probe before it) blocks in open();
// the watchdog fails the run as stage_timeout within its limit plus a few
// seconds, and the worker that replaces the stuck one finishes the batch.
TEST(BadInput, AStageBlockedOnAFifoTimesOut) {
  TempDir dir;
  ASSERT_EQ(mkfifo((dir / "pipe.mp4").c_str(), 0644), 0);
  WriteFile(dir / "l.csv", "video,id,start_frame,end_frame\npipe.mp4,pipe,0,29\n" + Cups() +
                               ",cups,0,29\n");
  WriteFile(dir / "t.toml", "[timeouts]\nfilters_analyze = 2\n[filters_analyze]\n"
                            "hand_detector = \"builtin\"\n");
  Queue(dir / "d.db", "filters_analyze", dir / "l.csv");
  const double seconds = RunWorker(dir / "d.db", {"--config", (dir / "t.toml").string()});
  EXPECT_LT(seconds, 2 + 20.0);
  auto runs = RunsById(dir / "d.db");
  EXPECT_EQ(runs["pipe"].state, RunState::kFailed);
  EXPECT_EQ(runs["pipe"].attempts, 1) << "a deterministic stage's timeout is not retried";
  EXPECT_THAT(runs["pipe"].error, HasSubstr("stage_timeout: filters_analyze"));
  EXPECT_THAT(runs["pipe"].error, HasSubstr("limit of 2 s"));
  EXPECT_THAT(runs["pipe"].error, HasSubstr("clip pipe"));
  EXPECT_EQ(runs["cups"].state, RunState::kDone);
}

// A model command that hangs: the bundle stage's own limit is an hour, the
// stage limit from [timeouts] is 2 s; the command's process group is killed
// with the worker.
TEST(BadInput, AHangingModelCommandTimesOutAndIsKilled) {
  TempDir dir;
  const std::string apple = (SharedData() / "videos" / "apple.mp4").string();
  WriteFile(dir / "l.csv", "video,id\n" + Cups() + ",hang\n" + apple + ",quick\n");
  WriteFile(dir / "t.toml",
            "[timeouts]\nbundle = 2\n[bundle]\n"
            "command = \"test {clip} = hang && sleep 6131; echo no model here; exit 3\"\n");
  Queue(dir / "d.db", "bundle", dir / "l.csv");
  const double seconds = RunWorker(dir / "d.db", {"--config", (dir / "t.toml").string()});
  EXPECT_LT(seconds, 2 + 20.0);
  auto runs = RunsById(dir / "d.db");
  EXPECT_EQ(runs["hang"].state, RunState::kFailed);
  EXPECT_EQ(runs["hang"].attempts, 1);
  EXPECT_THAT(runs["hang"].error, HasSubstr("stage_timeout: bundle ran past its limit of 2 s"));
  // The other clip ran its command to the end: a failed command is worth a
  // retry (attempts 3), unlike the timeout.
  EXPECT_EQ(runs["quick"].state, RunState::kFailed);
  EXPECT_EQ(runs["quick"].attempts, 3);
  EXPECT_THAT(runs["quick"].error, HasSubstr("bundle_command_failed"));
  EXPECT_EQ(ShellOk("pgrep -f 'slee[p] 6131' || true"), "") << "the hung command outlived its worker";
}

// A run that reports progress and then stands still is stopped once it has
// been still for timeouts.no_progress, long before its wall-clock limit (an
// hour for bundle); a command that keeps writing to its log runs on past
// that many seconds. A model command reports progress when its log grows.
TEST(BadInput, ARunThatStopsMakingProgressTimesOut) {
  TempDir dir;
  const std::string apple = (SharedData() / "videos" / "apple.mp4").string();
  WriteFile(dir / "l.csv", "video,id\n" + Cups() + ",stuck\n" + apple + ",talker\n");
  WriteFile(dir / "t.toml",
            "[timeouts]\nno_progress = 2\n[bundle]\ncommand = \""
            "if test {clip} = stuck; then echo loading; sleep 6133; fi; "
            "for i in 1 2 3 4 5 6 7 8; do echo step $i; sleep 0.5; done; exit 3\"\n");
  Queue(dir / "d.db", "bundle", dir / "l.csv");
  const double seconds = RunWorker(
      dir / "d.db", {"--config", (dir / "t.toml").string(), "--max-attempts", "1"});
  EXPECT_LT(seconds, 2 + 4 + 20.0);
  auto runs = RunsById(dir / "d.db");
  EXPECT_EQ(runs["stuck"].state, RunState::kFailed);
  EXPECT_THAT(runs["stuck"].error, HasSubstr("stage_timeout: bundle made no progress for 2 s"));
  EXPECT_THAT(runs["stuck"].error, HasSubstr("timeouts.no_progress"));
  // Four seconds of steps, each within the limit: the command ran to its end.
  EXPECT_EQ(runs["talker"].state, RunState::kFailed);
  EXPECT_THAT(runs["talker"].error, HasSubstr("bundle_command_failed"));
  EXPECT_THAT(runs["talker"].error, ::testing::Not(HasSubstr("stage_timeout")));
  EXPECT_EQ(ShellOk("pgrep -f 'slee[p] 6133' || true"), "") << "the stuck command outlived its worker";
}

// Videos no stage can judge fail at probe as unsupported_video, once, with
// the reason in words; a real video in the same batch passes.
TEST(BadInput, DegenerateVideosAreUnsupportedAtTheFirstAttempt) {
  TempDir dir;
  const std::string tiny = "ffmpeg -v error -y -f lavfi -i color=red:s=16x16:r=10 -frames:v 10 "
                           "-vf scale=1:1 ";
  const std::map<std::string, std::pair<std::string, std::string>> videos = {
      {"ffv1", {tiny + "-c:v ffv1 ", "tiny.mkv"}},
      {"mpeg4", {tiny + "-c:v mpeg4 ", "tiny_mpeg4.mp4"}},
      {"h264_444", {tiny + "-c:v libx264 -pix_fmt yuv444p ", "tiny_h264.mp4"}},
      {"mjpeg", {tiny + "-c:v mjpeg -pix_fmt yuvj444p ", "tiny.avi"}},
      {"raw", {tiny + "-c:v rawvideo ", "tiny.nut"}},
      {"audio", {"ffmpeg -v error -y -f lavfi -i sine=d=1 -c:a aac ", "audio.mp4"}},
      {"one_frame",
       {"ffmpeg -v error -y -f lavfi -i color=red:s=64x48:r=10 -frames:v 1 -c:v libx264 ",
        "one.mp4"}},
      {"too_wide",
       {"ffmpeg -v error -y -f lavfi -i color=red:s=17000x16:r=10 -frames:v 3 -c:v rawvideo ",
        "wide.nut"}},
  };
  std::string list = "video,id\n" + Cups() + ",cups\n";
  for (const auto& [id, how] : videos) {
    ShellOk(how.first + (dir / how.second).string());
    list += how.second + "," + id + "\n";
  }
  // A picture under a video's name.
  ShellOk("ffmpeg -v error -y -f lavfi -i color=blue:s=64x48 -frames:v 1 " +
          (dir / "still.png").string());
  fs::copy_file(dir / "still.png", dir / "still.mp4");
  list += "still.mp4,still\n";
  WriteFile(dir / "l.csv", list);
  Queue(dir / "d.db", "probe", dir / "l.csv");
  RunWorker(dir / "d.db");
  const std::map<std::string, std::string> reasons = {
      {"ffv1", "1x1 pixels is too small"}, {"mpeg4", "1x1 pixels is too small"},
      {"h264_444", "1x1 pixels is too small"}, {"mjpeg", "1x1 pixels is too small"},
      {"raw", "1x1 pixels is too small"}, {"audio", "audio only"},
      {"one_frame", "a single frame"}, {"too_wide", "17000x16 pixels is larger than any camera"},
      {"still", "a still image"}};
  auto runs = RunsById(dir / "d.db");
  for (const auto& [id, reason] : reasons) {
    EXPECT_EQ(runs[id].state, RunState::kFailed) << id;
    EXPECT_EQ(runs[id].attempts, 1) << id;
    EXPECT_THAT(runs[id].error, HasSubstr("unsupported_video: " + reason)) << id;
  }
  EXPECT_EQ(runs["cups"].state, RunState::kDone);
}

// Ingest: each bad row is named by file:line and field, the refused rows
// are counted by field, and the good rows go in.
TEST(BadInput, BadRowsAreNamedAndTheOtherRowsGoIn) {
  TempDir dir;
  const auto db = dir / "d.db";
  ASSERT_EQ(RunDoasido({"init", "--db", db.string()}).exit_code, 0);
  fs::create_symlink("loop_b.mp4", dir / "loop_a.mp4");
  fs::create_symlink("loop_a.mp4", dir / "loop_b.mp4");
  const std::string deep = std::string(100000, '[') + std::string(100000, ']');
  const std::string long_path = "/" + std::string(5000, 'x') + ".mp4";
  WriteFile(dir / "l.jsonl", "{\"video\": \"" + Cups() + "\", \"id\": \"good1\"}\n" +
                                 "{\"video\": \"loop_a.mp4\", \"id\": \"loop\"}\n" +
                                 "{\"video\": \"" + long_path + "\", \"id\": \"long\"}\n" +
                                 "{\"video\": \"x.mp4\", \"meta\": " + deep + "}\n" + deep + "\n" +
                                 "{\"video\": \"x.mp4\", \"n\": -11204112e1120}\n" +
                                 "{\"video\": \"" + Cups() +
                                 "\", \"id\": \"good2\", \"start_frame\": 5}\n");
  const auto r = RunDoasido({"ingest", "--db", db.string(), "--json", (dir / "l.jsonl").string()});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const Json s = Json::parse(r.out)[0];
  EXPECT_EQ(s["inserted"], 2);
  ASSERT_EQ(s["bad_rows"], 5) << r.out.substr(0, 2000);
  const Json& e = s["errors"];
  EXPECT_EQ(e[0]["line"], 2);
  EXPECT_THAT(e[0]["reason"].get<std::string>(), HasSubstr("Too many levels of symbolic links"));
  EXPECT_EQ(e[1]["line"], 3);
  EXPECT_THAT(e[1]["reason"].get<std::string>(), HasSubstr("File name too long"));
  EXPECT_THAT(e[1]["reason"].get<std::string>(), HasSubstr("(5005 characters)"));
  EXPECT_EQ(e[2]["line"], 4);
  EXPECT_THAT(e[2]["reason"].get<std::string>(), HasSubstr("json_too_deep"));
  EXPECT_EQ(e[3]["line"], 5);
  // A number past double's range (found by request_body_fuzz) is a bad row,
  // not the end of the ingest.
  EXPECT_EQ(e[4]["line"], 6);
  EXPECT_THAT(e[4]["reason"].get<std::string>(), HasSubstr("bad_json"));
  EXPECT_EQ(s["bad_rows_by_field"], Json({{"video", 2}, {"row", 3}}));
  EXPECT_EQ(RunsById(db).size(), 2u);
}

TEST(BadInput, VocBoxesThatCannotBeTrueAreRefusedWithTheirValues) {
  TempDir dir;
  auto xml = [](const std::string& box) {
    return "<annotation><size><width>640</width><height>480</height></size><object><name>hand"
           "</name><bndbox>" + box + "</bndbox><contactstate>3</contactstate></object>"
           "</annotation>";
  };
  const auto a = dir / "voc" / "Annotations";
  WriteFile(a / "k_v_good_frame000001.xml",
            xml("<xmin>10</xmin><ymin>10</ymin><xmax>60</xmax><ymax>80</ymax>"));
  WriteFile(a / "k_v_good_frame000002.xml",  // past the edge by rounding: kept
            xml("<xmin>600</xmin><ymin>10</ymin><xmax>642</xmax><ymax>80</ymax>"));
  WriteFile(a / "k_v_neg_frame000001.xml",
            xml("<xmin>60</xmin><ymin>10</ymin><xmax>20</xmax><ymax>80</ymax>"));
  WriteFile(a / "k_v_far_frame000001.xml",
            xml("<xmin>10</xmin><ymin>10</ymin><xmax>5000</xmax><ymax>80</ymax>"));
  const auto db = dir / "d.db";
  const auto r = RunDoasido({"ingest", "--db", db.string(), "--json", (dir / "voc").string()});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const Json s = Json::parse(r.out)[0];
  EXPECT_EQ(s["inserted"], 1);
  EXPECT_EQ(s["detections"], 2);
  ASSERT_EQ(s["bad_rows"], 2);
  std::string reasons;
  for (const auto& e : s["errors"]) {
    EXPECT_EQ(e["field"], "bndbox");
    reasons += e["file"].get<std::string>() + ": " + e["reason"].get<std::string>() + "\n";
  }
  EXPECT_THAT(reasons, HasSubstr("k_v_neg_frame000001.xml: empty or reversed box: xmin 60 ymin 10 "
                                 "xmax 20 ymax 80"));
  EXPECT_THAT(reasons, HasSubstr("k_v_far_frame000001.xml: box outside the image: xmin 10 ymin 10 "
                                 "xmax 5000 ymax 80 (image 640x480)"));
}

// An empty list is the same outcome in every format: refused whole
// (empty_list, exit 1), the other lists of the command still go in.
TEST(BadInput, AnEmptyListIsRefusedTheSameWayInEveryFormat) {
  TempDir dir;
  const auto db = dir / "d.db";
  WriteFile(dir / "good.csv", "video,id\n" + Cups() + ",cups\n");
  for (const std::string name : {"e.csv", "e.tsv", "e.jsonl", "e.json", "e.txt", "blank.csv"}) {
    WriteFile(dir / name, name == "blank.csv" ? " \n\n\t\n" : "");
    const auto r = RunDoasido(
        {"ingest", "--db", db.string(), (dir / name).string(), (dir / "good.csv").string()});
    EXPECT_EQ(r.exit_code, 1) << name;
    EXPECT_THAT(r.err, HasSubstr("empty_list: the list is empty")) << name;
    EXPECT_THAT(r.err, HasSubstr((dir / name).string())) << name;
  }
  EXPECT_EQ(RunsById(db).size(), 1u);
  // A FIFO named as a list is refused without being read (it would never end).
  ASSERT_EQ(mkfifo((dir / "pipe.csv").c_str(), 0644), 0);
  const auto fifo = RunDoasido({"ingest", "--db", db.string(), (dir / "pipe.csv").string()});
  EXPECT_EQ(fifo.exit_code, 1);
  EXPECT_THAT(fifo.err, HasSubstr("not_a_regular_file"));
}

// --config naming a missing file is an error (exit 2) for every command
// that takes it, and nothing runs.
TEST(BadInput, AMissingConfigFileIsAnErrorForEveryCommand) {
  TempDir dir;
  const auto db = dir / "d.db";
  WriteFile(dir / "good.csv", "video,id\n" + Cups() + ",cups\n");
  Queue(db, "noop", dir / "good.csv");
  const std::string missing = (dir / "missing.toml").string();
  const std::string d = db.string();
  for (const std::vector<std::string>& args :
       {std::vector<std::string>{"init", "--db", d}, {"run", "--db", d}, {"worker", "--db", d},
        {"status", "--db", d}, {"queue", "list", "--db", d},
        {"rethreshold", "--db", d}, {"report", "--db", d, "--out", (dir / "r").string()},
        {"ingest", "--db", d, (dir / "good.csv").string()}}) {
    std::vector<std::string> with = args;
    with.insert(with.end(), {"--config", missing});
    const auto r = RunDoasido(with);
    EXPECT_EQ(r.exit_code, 2) << args[0] << ": " << r.err;
    EXPECT_THAT(r.err, HasSubstr(missing)) << args[0];
  }
  auto runs = RunsById(db);
  EXPECT_EQ(runs["cups"].state, RunState::kPending) << "a command ran with a missing config";
}

}  // namespace
}  // namespace doasido
