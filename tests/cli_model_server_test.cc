// The bundle stage in server mode through `doasido run` (recon/bundle/model_server.h,
// tools/bundle_server.py as the model): 20 synthetic clips, two workers.
// Each worker starts its server once (counted in the server logs); every
// bundle equals the one the same stand-in writes as a per-clip command; a
// server that dies while holding a clip is restarted, that clip fails once
// with the log's tail and then passes, the others pass at the first attempt.
// A server that answers an error, hangs, or dies before it is ready fails
// only the clip it held, naming clip, file and field.
#include <algorithm>
#include <filesystem>
#include <fstream>
#include <map>
#include <regex>
#include <set>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "db/database.h"
#include "testing/db_dump.h"
#include "tests/test_util.h"

namespace doasido {
namespace {

using ::testing::HasSubstr;
using doasido::testing::QueryRows;
using doasido::testing::RunDoasido;
using doasido::testing::SourceDir;
using doasido::testing::TempDir;
using doasido::testing::WriteFile;

// Debian's python3, which has python3-numpy (a python3 earlier in PATH may not).
std::string Tool() { return "/usr/bin/python3 " + (SourceDir() / "tools/bundle_server.py").string(); }

// Synthetic clips with their ground-truth bundles; returns the clip list.
std::filesystem::path Synth(const TempDir& dir, int clips) {
  const auto synth = dir / "s";
  const auto r = RunDoasido({"synth", "--out", synth.string(), "--clips", std::to_string(clips),
                             "--frames", "24", "--width", "64", "--height", "48", "--mix",
                             "clean=1", "--seed", "11", "--no-annotations"});
  EXPECT_EQ(r.exit_code, 0) << r.err;
  return synth / "clips.csv";
}

// A database with the bundle stage alone, run over `list` with `bundle_toml`.
std::filesystem::path RunBundle(const TempDir& dir, const std::string& name,
                                const std::filesystem::path& list, const std::string& bundle_toml,
                                int max_attempts) {
  const auto db = dir / name / "d.db";
  std::filesystem::create_directories(db.parent_path());
  WriteFile(dir / name / "config.toml", "[bundle]\n" + bundle_toml);
  EXPECT_EQ(RunDoasido({"init", "--db", db.string(), "--pipeline", "bundle"}).exit_code, 0);
  const auto run =
      RunDoasido({"run", "--db", db.string(), "--config", (dir / name / "config.toml").string(),
                  "--jobs", "2", "--max-attempts", std::to_string(max_attempts), list.string()});
  EXPECT_EQ(run.exit_code, 0) << run.err;
  return db;
}

// Every file of a folder (command.log left out) by relative path.
std::map<std::string, std::string> Files(const std::filesystem::path& dir) {
  std::map<std::string, std::string> files;
  for (const auto& e : std::filesystem::recursive_directory_iterator(dir)) {
    if (!e.is_regular_file() || e.path().filename() == "command.log") continue;
    files[std::filesystem::relative(e.path(), dir).string()] =
        doasido::testing::ReadFile(e.path());
  }
  return files;
}

int Count(const std::string& text, const std::string& what) {
  int n = 0;
  for (size_t at = text.find(what); at != std::string::npos; at = text.find(what, at + 1)) ++n;
  return n;
}

// The server logs of a database folder, by file name.
std::map<std::string, std::string> ServerLogs(const std::filesystem::path& db) {
  std::map<std::string, std::string> logs;
  const auto dir = db.parent_path() / "logs";
  if (!std::filesystem::is_directory(dir)) return logs;
  for (const auto& e : std::filesystem::directory_iterator(dir)) {
    if (!e.is_regular_file()) continue;  // logs/<clip>/: failed runs' own logs
    logs[e.path().filename().string()] = doasido::testing::ReadFile(e.path());
  }
  return logs;
}

TEST(CliModelServer, TwentyClipsOneServerPerWorkerAndADeadServerRestarted) {
  TempDir dir;
  const auto list = Synth(dir, 20);
  const auto rows = doasido::testing::ReadCsv(list);
  ASSERT_EQ(rows.size(), 21u);
  const std::string victim = rows[6][1];  // the clip the server dies on

  const auto per_clip = RunBundle(
      dir, "command", list,
      "command = \"" + Tool() +
          " --load-s 0.2 --clip {clip} --video {video} --output {output} --first-frame "
          "{first_frame} --last-frame {last_frame} --fps {fps}\"\n",
      1);
  const auto served = RunBundle(dir, "server", list,
                                "server = \"" + Tool() + " --load-s 0.5 --die " + victim +
                                    " --once " + (dir / "once").string() + "\"\n",
                                3);

  Database command_db(per_clip.string()), server_db(served.string());
  std::map<std::string, StageRunRow> command_runs, server_runs;
  for (const auto& r : command_db.ListRuns({})) command_runs[r.external_id] = r;
  for (const auto& r : server_db.ListRuns({})) server_runs[r.external_id] = r;
  ASSERT_EQ(command_runs.size(), 20u);
  ASSERT_EQ(server_runs.size(), 20u);
  for (const auto& [clip, run] : server_runs) {
    ASSERT_EQ(run.state, RunState::kDone) << clip << " " << run.error;
    ASSERT_EQ(command_runs.at(clip).state, RunState::kDone) << command_runs.at(clip).error;
    EXPECT_EQ(run.attempts, clip == victim ? 2 : 1) << clip;
    EXPECT_EQ((*server_db.GetMeasurements(run.clip_id, "bundle"))["source"], "server");
    const auto mine = Files(server_db.ArtifactDir(run.clip_id, "bundle"));
    EXPECT_GE(mine.size(), 5u) << clip;
    EXPECT_TRUE(mine == Files(command_db.ArtifactDir(command_runs.at(clip).clip_id, "bundle")))
        << clip << ": the server's bundle differs from the per-clip command's";
  }

  // The one failed attempt, with the server log's tail, named.
  const auto failures = QueryRows(served, "SELECT c.external_id, e.detail FROM events e JOIN"
                                          " clips c ON c.id = e.clip_id WHERE e.kind IN"
                                          " ('retry', 'failed')");
  ASSERT_EQ(failures.size(), 1u);
  EXPECT_THAT(failures[0], HasSubstr(victim + "|bundle_command_failed"));
  EXPECT_THAT(failures[0], HasSubstr("the model server ended (exit status 3) while it held clip"));
  EXPECT_THAT(failures[0], HasSubstr("dying on purpose while holding clip " + victim));
  EXPECT_THAT(failures[0], HasSubstr("field bundle.server"));

  // One server per worker, plus the one restart; each log belongs to a worker.
  const auto logs = ServerLogs(served);
  ASSERT_GE(logs.size(), 1u);
  ASSERT_LE(logs.size(), 2u);
  int loads = 0, restarted = 0;
  for (const auto& [name, text] : logs) {
    EXPECT_THAT(name, ::testing::MatchesRegex("bundle-server-[0-9]+\\.log"));
    const int n = Count(text, "model loaded in 0.5 s");
    EXPECT_EQ(n, Count(text, "doasido: starting model server")) << text;
    loads += n;
    if (n == 2) {
      ++restarted;
      EXPECT_THAT(text, HasSubstr("dying on purpose"));
    } else {
      EXPECT_EQ(n, 1) << text;
    }
  }
  EXPECT_EQ(restarted, 1);
  EXPECT_EQ(loads, static_cast<int>(logs.size()) + 1);
}

TEST(CliModelServer, ErrorsHangsAndBrokenServersFailOnlyTheirClip) {
  TempDir dir;
  const auto list = Synth(dir, 4);
  const auto rows = doasido::testing::ReadCsv(list);
  ASSERT_EQ(rows.size(), 5u);
  const std::string fail = rows[1][1], hang = rows[2][1];
  const auto db = RunBundle(dir, "misbehave", list,
                            "server = \"" + Tool() + " --fail " + fail + " --hang " + hang +
                                "\"\ntimeout_s = 2\n",
                            1);
  Database check(db.string());
  std::map<std::string, StageRunRow> runs;
  for (const auto& r : check.ListRuns({})) runs[r.external_id] = r;
  ASSERT_EQ(runs.size(), 4u);
  EXPECT_EQ(runs.at(fail).state, RunState::kFailed);
  EXPECT_THAT(runs.at(fail).error, HasSubstr("bundle_command_failed: the server: CUDA out of memory"));
  EXPECT_THAT(runs.at(fail).error, HasSubstr("clip " + fail));
  EXPECT_EQ(runs.at(hang).state, RunState::kFailed);
  EXPECT_THAT(runs.at(hang).error, HasSubstr("bundle_timeout"));
  EXPECT_THAT(runs.at(hang).error, HasSubstr("hanging on purpose on clip " + hang));
  for (size_t i = 3; i < rows.size(); ++i) {
    EXPECT_EQ(runs.at(rows[i][1]).state, RunState::kDone) << runs.at(rows[i][1]).error;
  }

  // A server that dies before its ready line fails the clip and says so;
  // a retry would meet the same server, but the run is transient by design
  // (a busy GPU), so one attempt here.
  const auto broken = RunBundle(dir, "broken", list,
                                "server = \"echo loading >&2; exit 4\"\n", 1);
  Database b(broken.string());
  for (const auto& r : b.ListRuns({})) {
    EXPECT_EQ(r.state, RunState::kFailed);
    EXPECT_THAT(r.error, HasSubstr("the model server ended (exit status 4) while doasido waited for its ready line"));
    EXPECT_THAT(r.error, HasSubstr("loading"));
    EXPECT_THAT(r.error, HasSubstr("field bundle.server"));
  }
}

}  // namespace
}  // namespace doasido
