// Outputs never overwrite inputs (issue #42, core/output_path.h), through
// the built binary: every writing command refuses an output path that is the
// database, inside a dataset version, inside the artifact root, a device, or
// an existing file of another kind, naming it; the database stays byte for
// byte the same and still opens, the version still verifies. An earlier
// output of the same command is replaced only with --force.
#include <gtest/gtest.h>

#include <chrono>
#include <csignal>
#include <fstream>
#include <map>
#include <random>
#include <sstream>
#include <thread>

#include "dataset/version.h"
#include "testing/db_dump.h"
#include "tests/test_util.h"

namespace doasido {
namespace {

namespace fs = std::filesystem;
using testing::CommandResult;
using testing::QueryRows;
using testing::ReadFile;
using testing::RunDoasido;
using testing::TempDir;
using testing::WriteFile;

// Two clean clips through the kinematic chain, and a version of them.
class OutputGuard : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    dir_ = new TempDir();
    const fs::path synth = *dir_ / "s";
    ASSERT_EQ(RunDoasido({"synth", "--out", synth.string(), "--clips", "2", "--seed", "4",
                          "--frames", "24", "--width", "96", "--height", "72", "--mix", "clean=1"})
                  .exit_code,
              0);
    WriteFile(*dir_ / "run.toml",
              "[bundle]\ncommand = \"cp -r $(dirname $(dirname {video}))/bundles/$(basename "
              "{video} .mp4)/. {output}/\"\n");
    ASSERT_EQ(RunDoasido({"init", "--db", Db(), "--pipeline",
                          "download,probe,bundle,recon,retarget_kinematic"})
                  .exit_code,
              0);
    const auto run = RunDoasido({"run", "--db", Db(), "--config", (*dir_ / "run.toml").string(),
                                 (synth / "clips.csv").string()});
    ASSERT_EQ(run.exit_code, 0) << run.err;
    const auto made = RunDoasido({"dataset", "create", "--db", Db(), "--root", Root(), "--select",
                                  "all", "--no-thumbnails"});
    ASSERT_EQ(made.exit_code, 0) << made.err;
  }
  static void TearDownTestSuite() {
    delete dir_;
    dir_ = nullptr;
  }
  static std::string Db() { return (*dir_ / "d.db").string(); }
  static std::string Root() { return (*dir_ / "datasets").string(); }
  static fs::path Version() { return *dir_ / "datasets/default/v1"; }
  static std::string Trajectory() {
    return (*dir_ / "artifacts/1/retarget_kinematic/trajectory.json").string();
  }
  static std::string Bytes(const fs::path& p) { return ReadFile(p); }

  // Runs `args`, which must be refused with `code` naming `named`; the
  // database file and the version's manifest are byte for byte unchanged.
  void ExpectRefused(const std::vector<std::string>& args, const std::string& named,
                     const std::string& code = "unsafe_output") {
    const std::string db_before = Bytes(Db());
    const std::string manifest_before = Bytes(Version() / "manifest.json");
    const CommandResult r = RunDoasido(args);
    std::string line;
    for (const auto& a : args) line += a + " ";
    EXPECT_EQ(r.exit_code, 1) << line << r.out << r.err;
    EXPECT_NE(r.err.find(code), std::string::npos) << line << r.err;
    EXPECT_NE(r.err.find(named), std::string::npos) << line << r.err;
    EXPECT_TRUE(Bytes(Db()) == db_before) << line << ": the database changed";
    EXPECT_EQ(Bytes(Version() / "manifest.json"), manifest_before) << line;
  }
  // After each test: the database still opens, the version still verifies.
  void TearDown() override {
    EXPECT_EQ(RunDoasido({"status", "--db", Db()}).exit_code, 0);
    EXPECT_EQ(RunDoasido({"dataset", "verify", "--root", Root(), "v1"}).exit_code, 0);
  }

  static TempDir* dir_;
};
TempDir* OutputGuard::dir_ = nullptr;

// Every writing command, writing to `out`.
std::vector<std::vector<std::string>> Writers(const std::string& db, const std::string& root,
                                              const std::string& trajectory,
                                              const std::string& out) {
  return {
      {"dataset", "export", "--root", root, "v1", "--format", "robomimic", "--out", out},
      {"dataset", "export", "--root", root, "v1", "--format", "lerobot", "--no-videos", "--out",
       out},
      {"dataset", "create", "--db", db, "--root", out, "--select", "all", "--no-thumbnails"},
      {"deploy", "plan", "--trajectory", trajectory, "--no-replay", "--yaw-steps", "1",
       "--offset-steps", "1", "--out", out},
      {"deploy", "plan", "--db", db, "--clip", "1", "--no-replay", "--yaw-steps", "1",
       "--offset-steps", "1", "--out", out},
      {"report", "--db", db, "--no-thumbnails", "--out", out},
      {"shard", "--db", db, "--out", out},
      {"synth", "--clips", "1", "--out", out},
      {"hand", "import", "--mjcf", "/nonexistent/hand.xml", "--out", out},
      {"hand", "mirror", "shadow", "--out", out},
      {"hand", "check", "shadow", "--out", out},
      {"retarget-kinematic", "--keypoints", "/nonexistent.csv", "--out", out},
      {"deploy", "stream", "--plan", "/nonexistent/plan.json", "--dry-run", out},
  };
}

TEST_F(OutputGuard, EveryWriterRefusesTheDatabase) {
  for (const auto& args : Writers(Db(), Root(), Trajectory(), Db())) ExpectRefused(args, Db());
  // Its journal files too.
  ExpectRefused(
      {"deploy", "plan", "--trajectory", Trajectory(), "--no-replay", "--out", Db() + "-wal"},
      Db() + "-wal");
}

TEST_F(OutputGuard, EveryWriterRefusesAPlaceInsideAVersion) {
  const std::string manifest = (Version() / "manifest.json").string();
  const std::string episodes = (Version() / "episodes/new").string();
  for (const auto& args : Writers(Db(), Root(), Trajectory(), episodes)) {
    ExpectRefused(args, "inside the dataset version");
  }
  ExpectRefused(
      {"dataset", "export", "--root", Root(), "v1", "--format", "robomimic", "--out", manifest},
      manifest);
  // A dataset root inside a version would nest a dataset in it.
  ExpectRefused(
      {"dataset", "create", "--db", Db(), "--root", Version().string(), "--select", "all"},
      "inside the dataset version");
}

TEST_F(OutputGuard, EveryWriterRefusesTheArtifactRoot) {
  const std::string inside = (*dir_ / "artifacts/1/new").string();
  for (const auto& args : Writers(Db(), Root(), Trajectory(), inside)) {
    ExpectRefused(args, "inside the artifact root");
  }
  ExpectRefused(
      {"deploy", "plan", "--trajectory", Trajectory(), "--no-replay", "--out", Trajectory()},
      Trajectory());
}

TEST_F(OutputGuard, EveryWriterRefusesADevice) {
  for (const auto& args : Writers(Db(), Root(), Trajectory(), "/dev/null")) {
    ExpectRefused(args, "/dev/null");
  }
}

TEST_F(OutputGuard, AnExistingFileOfAnotherKindIsRefusedEvenWithForce) {
  const fs::path notes = *dir_ / "notes.txt";
  WriteFile(notes, "my notes\n");
  ExpectRefused({"deploy", "plan", "--trajectory", Trajectory(), "--no-replay", "--force", "--out",
                 notes.string()},
                "not an earlier output");
  ExpectRefused({"dataset", "export", "--root", Root(), "v1", "--format", "robomimic", "--out",
                 notes.string()},
                "not an earlier output");
  ExpectRefused({"report", "--db", Db(), "--force", "--out", notes.string()}, "is a file");
  const fs::path folder = *dir_ / "somefolder";
  WriteFile(folder / "keep.txt", "keep\n");
  ExpectRefused({"dataset", "export", "--root", Root(), "v1", "--format", "robomimic", "--out",
                 folder.string()},
                "is a folder");
  ExpectRefused({"synth", "--clips", "1", "--force", "--out", folder.string()},
                "not an earlier output");
  EXPECT_EQ(ReadFile(notes), "my notes\n");
  EXPECT_EQ(ReadFile(folder / "keep.txt"), "keep\n");
}

TEST_F(OutputGuard, AnEarlierOutputIsReplacedOnlyWithForce) {
  const fs::path plan = *dir_ / "plans/plan.json";
  fs::create_directories(plan.parent_path());
  const std::vector<std::string> args = {
      "deploy",         "plan", "--trajectory", Trajectory(), "--no-replay", "--yaw-steps", "1",
      "--offset-steps", "1",    "--out",        plan.string()};
  const auto first = RunDoasido(args);
  ASSERT_TRUE(fs::exists(plan)) << first.err;
  const std::string written = ReadFile(plan);
  ExpectRefused(args, "--force replaces it", "output_exists");
  EXPECT_EQ(ReadFile(plan), written);
  auto forced = args;
  forced.push_back("--force");
  RunDoasido(forced);
  EXPECT_EQ(Json::parse(ReadFile(plan))["format"], "doasido_deploy_plan");
  // Nothing but the plan was left beside it (the temporary file is gone).
  EXPECT_EQ(std::distance(fs::directory_iterator(plan.parent_path()), fs::directory_iterator()), 1);

  const fs::path report = *dir_ / "report";
  ASSERT_EQ(
      RunDoasido({"report", "--db", Db(), "--no-thumbnails", "--out", report.string()}).exit_code,
      0);
  ExpectRefused({"report", "--db", Db(), "--no-thumbnails", "--out", report.string()},
                "--force replaces it", "output_exists");
  const auto again =
      RunDoasido({"report", "--db", Db(), "--no-thumbnails", "--force", "--out", report.string()});
  EXPECT_EQ(again.exit_code, 0) << again.err;
  EXPECT_TRUE(fs::exists(report / "report.html"));
  EXPECT_NE(again.out.find((report / "report.html").string()), std::string::npos) << again.out;
}

TEST_F(OutputGuard, ARelativeTrajectoryResolvesAgainstTheWorkingDirectory) {
  const std::string command = "cd '" + dir_->path().string() + "' && '" +
                              testing::DoasidoBin().string() +
                              "' deploy plan --trajectory artifacts/1/retarget_kinematic/"
                              "trajectory.json --yaw-steps 1 --offset-steps 1 --out rel.json"
                              " 2>&1; echo rc=$?";
  const std::string out = testing::ShellOk(command);
  EXPECT_TRUE(fs::exists(*dir_ / "rel.json")) << out;
  const Json plan = Json::parse(ReadFile(*dir_ / "rel.json"));
  EXPECT_EQ(plan["source"], (*dir_ / "artifacts/1/retarget_kinematic/trajectory.json").string());
}

}  // namespace
}  // namespace doasido

namespace doasido {
namespace {

// The hand commands (issue #42, finding 4): an earlier hand is replaced
// whole (a killed `hand mirror --force` leaves the old hand or the new one,
// never a mix), an output folder that holds the command's input is
// refused, and `hand check` replaces its pictures only with --force.
std::map<std::string, std::string> FolderBytes(const fs::path& dir) {
  std::map<std::string, std::string> out;
  for (const auto& e : fs::recursive_directory_iterator(dir)) {
    if (e.is_regular_file()) out[fs::relative(e.path(), dir).string()] = ReadFile(e.path());
  }
  return out;
}

TEST_F(OutputGuard, HandsAreReplacedWholeAndNeverOverTheirInput) {
  const fs::path hands = *dir_ / "hands";
  const fs::path left = hands / "left";
  const std::vector<std::string> mirror = {"hand", "mirror", "shadow", "--out", left.string()};
  const auto first = RunDoasido(mirror);
  ASSERT_EQ(first.exit_code, 0) << first.err;
  const auto written = FolderBytes(left);
  fs::path description;
  for (const auto& [name, bytes] : written) {
    if (fs::path(name).extension() == ".json") description = left / name;
    EXPECT_EQ(bytes.find(".tmp-"), std::string::npos) << name << " names the temporary folder";
  }
  ASSERT_FALSE(description.empty());
  ExpectRefused(mirror, "--force replaces it", "output_exists");
  // The output folder holds the input: replacing it would delete the input.
  ExpectRefused({"hand", "mirror", description.string(), "--force", "--out", left.string()},
                "holds the command's input");
  ExpectRefused({"hand", "import", "--mjcf", fs::path(description).replace_extension(".xml").string(),
                 "--force", "--out", left.string()},
                "holds the command's input");
  EXPECT_EQ(FolderBytes(left), written);

  // Killed at random moments while replacing: the old hand or the new one.
  auto forced = mirror;
  forced.push_back("--force");
  const auto t0 = std::chrono::steady_clock::now();
  ASSERT_EQ(RunDoasido(forced).exit_code, 0);
  const double full_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  std::mt19937 rng(42);
  for (int kill = 0; kill < 4; ++kill) {
    std::vector<std::string> argv = {testing::DoasidoBin().string()};
    argv.insert(argv.end(), forced.begin(), forced.end());
    const int pid = testing::Spawn(argv, *dir_ / "mirror.log");
    std::this_thread::sleep_for(std::chrono::duration<double>(
        std::uniform_real_distribution<double>(0.0, full_s)(rng)));
    ::kill(pid, SIGKILL);
    testing::WaitFor(pid);
    EXPECT_EQ(FolderBytes(left), written) << "kill " << kill << ": the hand is not whole";
    const auto again = RunDoasido(forced);
    EXPECT_EQ(again.exit_code, 0) << again.err;
    EXPECT_EQ(FolderBytes(left), written);
  }
  for (const auto& e : fs::directory_iterator(hands)) {
    EXPECT_EQ(e.path().filename().string().find(".tmp-"), std::string::npos) << e.path();
  }

  // hand check's pictures: replaced only with --force.
  const fs::path pictures = *dir_ / "pictures";
  const std::vector<std::string> check = {"hand", "check", "shadow", "--out", pictures.string()};
  ASSERT_EQ(RunDoasido(check).exit_code, 0);
  const auto drawn = FolderBytes(pictures);
  ASSERT_EQ(drawn.size(), 2u);
  ExpectRefused(check, "--force replaces it", "output_exists");
  auto check_forced = check;
  check_forced.push_back("--force");
  EXPECT_EQ(RunDoasido(check_forced).exit_code, 0);
  EXPECT_EQ(FolderBytes(pictures), drawn);
}

}  // namespace
}  // namespace doasido
