// The named pipelines: `doasido init` without --pipeline is the whole chain
// (filters -> hands -> bundle -> recon -> retarget_kinematic -> retarget),
// and every `doasido init ... --pipeline ...` line of README.md, docs/*.md
// and the --help texts runs as written on a synthetic sample.
//
// The whole chain runs on 8 clean synthetic clips (seed 1, 60 frames) with
// their ground-truth bundles (tools/ground_truth_bundle.sh) and the `fast`
// dynamics preset: every stage runs, no clip is rejected for the side of its
// hand (a lone left hand is mirrored with its object: `left_mirrored`), and
// dynamics succeeds on at least three quarters of the clips that reach it.
// Measured 2026-11-28 on the shared 2-core machine (8 engineers): 5 min 03 s
// user + 3 s sys CPU for the whole test (synth 236 s and run 1040 s of wall
// under that load); 7 of 7 clips with an object succeeded, 2 left hands
// mirrored, one clip stops at interaction (no_interaction).
#include <gtest/gtest.h>

#include <chrono>
#include <cstdio>
#include <fstream>
#include <map>
#include <regex>
#include <set>
#include <sstream>

#include "core/config.h"
#include "stages/dynamic_stage.h"
#include "stages/kinematic_stage.h"
#include "stages/stage_registry.h"
#include "testing/db_dump.h"
#include "tests/test_util.h"

namespace doasido {
namespace {

namespace fs = std::filesystem;
using testing::QueryRows;
using testing::ReadFile;
using testing::RunDoasido;
using testing::SourceDir;
using testing::TempDir;
using testing::WriteFile;

// The config every run here uses: ground-truth bundles for the synthetic
// clips, and the fastest dynamics preset (the paper's is minutes a second).
std::string ChainConfig() {
  return "[bundle]\ncommand = \"sh '" + (SourceDir() / "tools/ground_truth_bundle.sh").string() +
         "' {video} {output}\"\n\n[retarget]\npreset = \"fast\"\n";
}

double Seconds(std::chrono::steady_clock::time_point since) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - since).count();
}

// Every pipeline a `doasido init ... --pipeline P` line of `text` names.
std::set<std::string> DocumentedPipelines(const std::string& text) {
  static const std::regex kLine(R"(doasido init\b[^\n]*?--pipeline[ =]([A-Za-z0-9_,]+))");
  std::set<std::string> out;
  for (auto it = std::sregex_iterator(text.begin(), text.end(), kLine); it != std::sregex_iterator();
       ++it) {
    out.insert((*it)[1].str());
  }
  return out;
}

// (stage, state, verdict, reason) of every run of the database, by clip.
std::map<std::string, std::vector<std::vector<std::string>>> RunsByClip(const fs::path& db) {
  std::map<std::string, std::vector<std::vector<std::string>>> out;
  const auto rows = QueryRows(db,
                              "SELECT c.external_id, r.stage, r.state, IFNULL(r.verdict, ''),"
                              " IFNULL(r.reason, '') FROM stage_runs r JOIN clips c"
                              " ON c.id = r.clip_id ORDER BY c.external_id, r.position");
  for (const auto& row : rows) {
    std::vector<std::string> fields;
    std::stringstream line(row);
    for (std::string f; std::getline(line, f, '|');) fields.push_back(f);
    fields.resize(5);
    out[fields[0]].push_back({fields.begin() + 1, fields.end()});
  }
  return out;
}

TEST(PipelinePresets, EveryDocumentedInitPipelineRunsAsWritten) {
  std::map<std::string, std::string> where;  // pipeline -> first file naming it
  std::vector<fs::path> files = {SourceDir() / "README.md"};
  for (const auto& entry : fs::directory_iterator(SourceDir() / "docs")) {
    if (entry.path().extension() == ".md") files.push_back(entry.path());
  }
  for (const auto& file : files) {
    for (const auto& p : DocumentedPipelines(ReadFile(file))) where.emplace(p, file.filename());
  }
  for (const char* command : {"init", "run"}) {
    const auto help = RunDoasido({command, "--help"});
    ASSERT_EQ(help.exit_code, 0) << help.err;
    for (const auto& p : DocumentedPipelines(help.out)) where.emplace(p, std::string(command) + " --help");
  }
  // The ones this change wrote, at least: the filtering job, the hand-only chain.
  ASSERT_TRUE(where.count(stages::kPresetFilters)) << "no `--pipeline filters` line documented";
  ASSERT_TRUE(where.count("filters,hands,bundle,recon,retarget_kinematic"));

  TempDir dir;
  testing::SynthPool(dir / "synth", 1, 1, 30, 640, 480, "clean=1");
  WriteFile(dir / "chain.toml", ChainConfig());
  int i = 0;
  for (const auto& [pipeline, file] : where) {
    SCOPED_TRACE(pipeline + " (" + file + ")");
    const fs::path db = dir / ("p" + std::to_string(i++)) / "d.db";
    const auto start = std::chrono::steady_clock::now();
    const auto init = RunDoasido({"init", "--db", db.string(), "--pipeline", pipeline});
    ASSERT_EQ(init.exit_code, 0) << init.err;
    const auto run = RunDoasido({"run", "--db", db.string(), "--jobs", "2", "--config",
                                 (dir / "chain.toml").string(), (dir / "synth/clips.csv").string()});
    ASSERT_EQ(run.exit_code, 0) << run.err;
    // The clip went through every stage of the pipeline, each run done.
    std::vector<std::string> words;
    std::stringstream list(pipeline);
    for (std::string w; std::getline(list, w, ',');) words.push_back(w);
    const auto expanded = stages::ExpandPipeline(words);
    const auto runs = RunsByClip(db);
    ASSERT_EQ(runs.size(), 1u);
    const auto& clip_runs = runs.begin()->second;
    ASSERT_EQ(clip_runs.size(), expanded.size());
    for (size_t s = 0; s < expanded.size(); ++s) {
      EXPECT_EQ(clip_runs[s][0], expanded[s]);
      EXPECT_EQ(clip_runs[s][1], "done") << expanded[s];
      EXPECT_NE(clip_runs[s][2], "reject") << expanded[s] << ": " << clip_runs[s][3];
    }
    std::printf("%-75s %-14s %5.1f s\n", pipeline.c_str(), file.c_str(), Seconds(start));
  }
}

TEST(PipelinePresets, PresetWordsExpandAndRepeatsAreRefusedByName) {
  TempDir dir;
  const auto twice = RunDoasido({"init", "--db", (dir / "a.db").string(), "--pipeline", "default,bundle"});
  EXPECT_NE(twice.exit_code, 0);
  EXPECT_NE(twice.err.find("'bundle' is listed twice (preset 'default' holds it)"), std::string::npos)
      << twice.err;
  EXPECT_FALSE(fs::exists(dir / "a.db"));  // refused before the database is made
  const auto unknown = RunDoasido({"init", "--db", (dir / "b.db").string(), "--pipeline", "filter"});
  EXPECT_NE(unknown.exit_code, 0);
  EXPECT_NE(unknown.err.find("presets: default, filters"), std::string::npos) << unknown.err;
  ASSERT_EQ(RunDoasido({"init", "--db", (dir / "c.db").string(), "--pipeline", "filters,hands"}).exit_code, 0);
  std::vector<std::string> expected = stages::FiltersPipeline();
  expected.push_back("hands");
  EXPECT_EQ(QueryRows(dir / "c.db", "SELECT stage FROM pipeline ORDER BY position"), expected);
}

TEST(PipelinePresets, DefaultInitRunsTheWholeChainOnEightCleanClips) {
  TempDir dir;
  const auto start = std::chrono::steady_clock::now();
  testing::SynthPool(dir / "synth", 8, 1, 60, 640, 480, "clean=1");
  const double synth_s = Seconds(start);
  WriteFile(dir / "chain.toml", ChainConfig());
  const fs::path db = dir / "d.db";
  ASSERT_EQ(RunDoasido({"init", "--db", db.string()}).exit_code, 0);
  const auto pipeline = QueryRows(db, "SELECT stage FROM pipeline ORDER BY position");
  EXPECT_EQ(pipeline, stages::DefaultPipeline());
  ASSERT_EQ(pipeline.back(), retarget::kRetargetStageName);
  const auto run_start = std::chrono::steady_clock::now();
  const auto run = RunDoasido({"run", "--db", db.string(), "--jobs", "2", "--config",
                               (dir / "chain.toml").string(), (dir / "synth/clips.csv").string()});
  ASSERT_EQ(run.exit_code, 0) << run.err;
  const double run_s = Seconds(run_start);

  // Every stage ran; no clip stopped for the side of its hand, none failed.
  EXPECT_EQ(QueryRows(db, "SELECT COUNT(*) FROM stage_runs WHERE state != 'done'"),
            std::vector<std::string>{"0"});
  EXPECT_EQ(QueryRows(db, "SELECT COUNT(*) FROM stage_runs WHERE reason = 'no_right_hand'"),
            std::vector<std::string>{"0"});
  for (const auto& stage : pipeline) {
    EXPECT_NE(QueryRows(db, "SELECT COUNT(*) FROM stage_runs WHERE state = 'done' AND stage = '" +
                                stage + "'"),
              std::vector<std::string>{"0"})
        << stage << " never ran";
  }
  // Per clip: its hand in the ground truth, the hand retargeted, dynamics.
  int reached = 0, succeeded = 0, mirrored = 0;
  std::printf("%-10s %-6s %-14s %-20s %-8s %s\n", "clip", "hand", "retargeted", "retarget",
              "e_pos m", "stage seconds (hands, recon, kinematic, retarget)");
  for (const auto& [clip, runs] : RunsByClip(db)) {
    const Json gt = Json::parse(ReadFile(dir / "synth/gt" / (clip + ".json")));
    const Json& scene = gt["scenes"][0];
    const std::string side = scene["two_hands"].get<bool>() ? "both" : scene["active_hand"].get<std::string>();
    const auto kinematic = QueryRows(db, "SELECT json_extract(m.data, '$." +
                                             std::string(stages::kMeasureRetargetedHand) +
                                             "') FROM measurements m JOIN clips c ON c.id = m.clip_id"
                                             " WHERE c.external_id = '" + clip +
                                             "' AND m.stage = 'retarget_kinematic'");
    const std::string hand = kinematic.empty() ? "-" : kinematic[0];
    if (hand != "-" && side != "both") {
      EXPECT_EQ(hand, side == "left" ? "left_mirrored" : "right") << clip;
    }
    mirrored += hand == "left_mirrored";
    const auto& last = runs.back();
    std::string outcome = "-", e_pos = "-";
    if (last[0] == retarget::kRetargetStageName && last[3] != stages::kReasonHandOnlyKinematic) {
      ++reached;
      succeeded += last[2] == "pass";
      outcome = last[2] == "pass" ? "success" : last[3];
      e_pos = QueryRows(db, "SELECT printf('%.3f', json_extract(m.data, '$.e_pos')) FROM measurements m"
                            " JOIN clips c ON c.id = m.clip_id WHERE c.external_id = '" + clip +
                            "' AND m.stage = 'retarget'")[0];
    } else if (last[0] == retarget::kRetargetStageName) {
      outcome = last[3];
    } else {
      outcome = "stopped at " + last[0] + " " + last[3];
    }
    const auto seconds = QueryRows(db, "SELECT group_concat(s, ', ') FROM (SELECT printf('%.1f',"
                                       " r.duration_s) AS s FROM stage_runs r JOIN clips c ON c.id ="
                                       " r.clip_id WHERE c.external_id = '" + clip + "' AND r.stage IN"
                                       " ('hands', 'recon', 'retarget_kinematic', 'retarget')"
                                       " ORDER BY r.position)");
    std::printf("%-10s %-6s %-14s %-20s %-8s %s\n", clip.c_str(), side.c_str(), hand.c_str(),
                outcome.c_str(), e_pos.c_str(), seconds.empty() ? "" : seconds[0].c_str());
  }
  std::printf("synth %.1f s, run %.1f s; dynamics on %d clips with an object: %d succeeded; %d "
              "left hands mirrored\n",
              synth_s, run_s, reached, succeeded, mirrored);
  ASSERT_GE(reached, 4) << "too few clips reached dynamics to judge";
  EXPECT_GE(4 * succeeded, 3 * reached);
}

}  // namespace
}  // namespace doasido
