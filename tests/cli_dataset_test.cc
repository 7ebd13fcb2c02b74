// `doasido dataset` end to end through the built binary: synthetic clips
// with their ground-truth bundles -> `doasido run` through the filters,
// bundle, recon and retarget_kinematic -> `dataset create` v1 -> a person
// verifies one trajectory and `doasido rethreshold` applies a stricter
// out-of-frame limit -> v2. `dataset diff` must list exactly the episodes
// whose verdicts changed, `verify` must catch one changed byte, the
// robomimic export is read back by Debian's h5py, and `dataset create`
// killed with SIGKILL at random points never leaves a partial version.
#include <chrono>
#include <csignal>
#include <fstream>
#include <map>
#include <random>
#include <sstream>
#include <set>
#include <thread>

#include <sys/wait.h>
#include <unistd.h>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "dataset/version.h"
#include "dataset/version_files.h"
#include "dataset/version_store.h"
#include "db/database.h"
#include "ingest/file_sha256.h"
#include "stages/kinematic_stage.h"
#include "robot/trajectory/format.h"
#include "tests/test_util.h"

namespace doasido {
namespace {

namespace fs = std::filesystem;
using ::testing::HasSubstr;
using doasido::testing::RunDoasido;
using doasido::testing::TempDir;
using doasido::testing::WriteFile;

constexpr const char* kPipeline =
    "download,probe,filters_analyze,shot_boundary,interaction,out_of_frame,activity,"
    "camera_motion,bundle,recon,retarget_kinematic";

// One pool run through the whole pipeline, shared by the tests (read-only
// for all but the first, which works on its own copy).
class CliDataset : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    dir_ = new TempDir();
    const fs::path synth = *dir_ / "s";
    testing::SynthPool(synth, 6, 3, 40, 320, 240, "clean=0.5,no_contact=0.25,static=0.25");
    WriteFile(*dir_ / "run.toml", testing::SyntheticBundleConfig());
    ASSERT_EQ(RunDoasido({"init", "--db", Db(), "--pipeline", kPipeline}).exit_code, 0);
    const auto run = RunDoasido({"run", "--db", Db(), "--jobs", "2", "--config",
                                 (*dir_ / "run.toml").string(), synth.string()});
    ASSERT_EQ(run.exit_code, 0) << run.err;
  }
  static void TearDownTestSuite() {
    delete dir_;
    dir_ = nullptr;
  }
  static std::string Db() { return (*dir_ / "d.db").string(); }
  static TempDir* dir_;
};
TempDir* CliDataset::dir_ = nullptr;

std::set<std::int64_t> Clips(const dataset::Manifest& m) {
  std::set<std::int64_t> out;
  for (const auto& e : m.episodes) out.insert(e.clip_id);
  return out;
}

TEST_F(CliDataset, VersionsDiffVerifyAndRobomimic) {
  TempDir work;
  const std::string db = (work / "d.db").string();
  fs::copy_file(Db(), db);
  fs::copy(*dir_ / "artifacts", work / "artifacts", fs::copy_options::recursive);
  fs::create_directory_symlink(*dir_ / "s", work / "s");  // videos are stored relative to the db
  const std::string root = (work / "datasets").string();

  auto v1_run = RunDoasido({"dataset", "create", "--db", db, "--root", root, "--select", "all",
                            "--no-thumbnails", "--name", "pour"});
  ASSERT_EQ(v1_run.exit_code, 0) << v1_run.err;
  const dataset::Manifest v1 = dataset::ReadManifest(work / "datasets/pour/v1");
  ASSERT_GE(v1.episodes.size(), 2u) << v1_run.out;
  EXPECT_EQ(v1.episodes.size() + v1.excluded.size(), 6u);
  EXPECT_EQ(RunDoasido({"dataset", "verify", "--root", root, "--name", "pour", "v1"}).exit_code, 0);
  for (const auto& e : v1.episodes) {
    EXPECT_TRUE(fs::exists(work / "datasets/pour/v1/episodes" / e.id / "trajectory.json"));
    EXPECT_TRUE(fs::exists(work / "datasets/pour/v1/episodes" / e.id / "recon"));
    EXPECT_EQ(e.frames, 40);
    EXPECT_EQ(e.stages.size(), 11u);
  }
  EXPECT_TRUE(fs::exists(work / "datasets/pour/v1/playbook/report.html"));

  // A stricter out-of-frame limit between the kept clips' cut fractions.
  std::map<std::int64_t, double> cut;
  {
    Database d(db);
    for (const auto& e : v1.episodes) {
      cut[e.clip_id] = (*d.GetMeasurements(e.clip_id, "out_of_frame"))["summary"]["cut_fraction"];
    }
  }
  double lo = 1, hi = 0;
  for (const auto& [clip, c] : cut) lo = std::min(lo, c), hi = std::max(hi, c);
  ASSERT_LT(lo, hi) << "the synthetic pool must hold kept clips with different cut fractions";
  const double limit = (lo + hi) / 2;
  WriteFile(work / "strict.toml", "[out_of_frame]\nreject_cut_fraction = " + std::to_string(limit) +
                                      "\nflag_cut_fraction = " + std::to_string(limit) + "\n");
  std::int64_t verified = 0;
  for (const auto& [clip, c] : cut) {
    if (c < limit) verified = clip;
  }
  {
    Database d(db);
    d.RecordVerification(verified, retarget::kKinematicStageName, "alice", true, "follows the mug",
                         ingest::FileSha256(d.ArtifactDir(verified, retarget::kKinematicStageName) /
                                            "trajectory.json"));
  }
  const auto re = RunDoasido({"rethreshold", "--db", db, "--config", (work / "strict.toml").string()});
  ASSERT_EQ(re.exit_code, 0) << re.err;
  std::set<std::int64_t> expect_removed;
  {
    Database d(db);
    for (const auto& [clip, c] : cut) {
      for (const auto& r : d.ListRuns({.stage = "out_of_frame", .clip = clip})) {
        if (r.verdict != "pass") expect_removed.insert(clip);
      }
    }
  }
  ASSERT_FALSE(expect_removed.empty());

  ASSERT_EQ(RunDoasido({"dataset", "create", "--db", db, "--root", root, "--select", "all",
                        "--no-thumbnails", "--name", "pour"})
                .exit_code,
            0);
  const dataset::Manifest v2 = dataset::ReadManifest(work / "datasets/pour/v2");
  EXPECT_EQ(v2.parent, "v1");
  EXPECT_EQ(v2.episodes.size(), v1.episodes.size() - expect_removed.size());

  const auto diff = RunDoasido({"dataset", "diff", "--root", root, "--name", "pour", "v1", "v2", "--json"});
  ASSERT_EQ(diff.exit_code, 0) << diff.err;
  std::set<std::int64_t> removed, changed;
  for (const Json& c : Json::parse(diff.out)) {
    const std::string kind = c["change"];
    const std::string reasons = c["reasons"].dump();
    if (kind == "removed") {
      removed.insert(c["clip_id"].get<std::int64_t>());
      EXPECT_THAT(reasons, HasSubstr("out_of_frame: re-threshold")) << reasons;
      EXPECT_THAT(reasons, HasSubstr("pass -> reject")) << reasons;
    } else {
      EXPECT_EQ(kind, "changed") << c.dump();
      changed.insert(c["clip_id"].get<std::int64_t>());
      EXPECT_THAT(reasons, HasSubstr("verified by alice")) << reasons;
    }
  }
  EXPECT_EQ(removed, expect_removed);
  EXPECT_EQ(changed, std::set<std::int64_t>{verified});
  const auto text = RunDoasido({"dataset", "diff", "--root", root, "--name", "pour", "v1", "v2"});
  EXPECT_THAT(text.out, HasSubstr("v1 -> v2: 0 added, " + std::to_string(expect_removed.size()) +
                                  " removed, 1 changed"));

  // --select verified takes exactly the trajectory the person accepted.
  ASSERT_EQ(RunDoasido({"dataset", "create", "--db", db, "--root", root, "--select", "verified",
                        "--no-thumbnails", "--name", "pour"})
                .exit_code,
            0);
  const dataset::Manifest v3 = dataset::ReadManifest(work / "datasets/pour/v3");
  EXPECT_EQ(Clips(v3), std::set<std::int64_t>{verified});
  ASSERT_TRUE(v3.episodes[0].verification);
  EXPECT_EQ(v3.episodes[0].verification->reviewer, "alice");

  // robomimic, read back by h5py.
  const fs::path h5 = work / "pour.hdf5";
  const auto ex = RunDoasido({"dataset", "export", "--root", root, "--name", "pour", "v2",
                              "--format", "robomimic", "--out", h5.string()});
  ASSERT_EQ(ex.exit_code, 0) << ex.err;
  WriteFile(work / "read.py", R"PY(import h5py, json, sys
f = h5py.File(sys.argv[1], 'r')
d = f['data']
out = {'total': int(d.attrs['total']), 'env_args': json.loads(d.attrs['env_args']),
       'mask': {k: [x.decode() for x in f['mask'][k][()]] for k in f['mask']}, 'demos': {}}
for name in d:
    g = d[name]
    out['demos'][name] = {'num_samples': int(g.attrs['num_samples']),
        'episode_id': g.attrs['episode_id'].decode(),
        'keys': sorted(g.keys()), 'obs': sorted(g['obs'].keys()),
        'actions': g['actions'][()].tolist(), 'states': g['states'][()].tolist(),
        'rewards': g['rewards'][()].tolist(), 'dones': g['dones'][()].tolist(),
        'joint_pos': g['obs/robot0_joint_pos'][()].tolist(),
        'next_joint_pos': g['next_obs/robot0_joint_pos'][()].tolist(),
        'object': g['obs/object'][()].tolist()}
print(json.dumps(out))
)PY");
  const fs::path json_out = work / "h5.json";
  ASSERT_EQ(std::system(("/usr/bin/python3 " + (work / "read.py").string() + " " + h5.string() +
                         " > " + json_out.string())
                            .c_str()),
            0);
  std::ifstream in(json_out);
  const Json got = Json::parse(in);
  ASSERT_EQ(got["demos"].size(), v2.episodes.size());
  std::int64_t total = 0;
  std::map<std::string, std::set<std::string>> mask;
  for (const auto& [split, demos] : got["mask"].items()) {
    for (const auto& d : demos) mask[split].insert(d.get<std::string>());
  }
  for (const auto& e : v2.episodes) {
    const std::string name = "demo_" + std::to_string(e.index);
    const Json& demo = got["demos"][name];
    const retarget::HandTrajectory t =
        retarget::ReadTrajectoryJson(work / "datasets/pour/v2/episodes" / e.id / "trajectory.json");
    const size_t n = t.qpos.size(), nq = t.qpos[0].size();
    ASSERT_EQ(demo["num_samples"], n);
    EXPECT_EQ(demo["episode_id"], e.id);
    EXPECT_EQ(demo["keys"], (Json{"actions", "dones", "next_obs", "obs", "rewards", "states"}));
    EXPECT_EQ(demo["obs"], (Json{"hand_keypoints", "object", "robot0_joint_pos"}));
    for (size_t f = 0; f < n; ++f) {
      for (size_t j = 0; j < nq; ++j) {
        ASSERT_EQ(demo["joint_pos"][f][j].get<double>(), t.qpos[f][j]);
        ASSERT_EQ(demo["states"][f][j].get<double>(), t.qpos[f][j]);
        ASSERT_EQ(demo["actions"][f][j].get<double>(), t.qpos[std::min(f + 1, n - 1)][j]);
        ASSERT_EQ(demo["next_joint_pos"][f][j].get<double>(), t.qpos[std::min(f + 1, n - 1)][j]);
      }
      EXPECT_EQ(demo["object"][f][0].get<double>(), t.object_poses[f].t.x());
      EXPECT_EQ(demo["object"][f][3].get<double>(), t.object_poses[f].q.w());
      EXPECT_EQ(demo["states"][f][nq + 2].get<double>(), t.object_poses[f].t.z());
      EXPECT_EQ(demo["dones"][f], f + 1 == n ? 1 : 0);
      EXPECT_EQ(demo["rewards"][f], f + 1 == n ? 1.0 : 0.0);
    }
    EXPECT_EQ(mask[e.split].count(name), 1u) << name;
    total += static_cast<std::int64_t>(n);
  }
  EXPECT_EQ(got["total"], total);
  EXPECT_EQ(got["env_args"]["env_kwargs"]["embodiment"], v2.episodes[0].embodiment);

  // LeRobot: one row per trajectory frame, one video frame per row.
  const auto lr = RunDoasido({"dataset", "export", "--root", root, "--name", "pour", "v2",
                              "--format", "lerobot", "--out", (work / "lerobot").string()});
  ASSERT_EQ(lr.exit_code, 0) << lr.err;
  std::ifstream info_file(work / "lerobot/meta/info.json");
  const Json info = Json::parse(info_file);
  EXPECT_EQ(info["total_episodes"], v2.episodes.size());
  EXPECT_EQ(info["total_frames"], total);
  EXPECT_EQ(info["robot_type"], v2.episodes[0].embodiment);
  EXPECT_EQ(info["features"]["observation.images.source"]["shape"], (Json{240, 320, 3}));
  // Exporting again replaces the complete export whole; a folder that is
  // not an export is never replaced.
  const auto again = RunDoasido({"dataset", "export", "--root", root, "--name", "pour", "v2",
                                 "--format", "lerobot", "--out", (work / "lerobot").string()});
  EXPECT_EQ(again.exit_code, 0) << again.err;
  EXPECT_TRUE(fs::exists(work / "lerobot/meta/info.json"));
  WriteFile(work / "notes/todo.txt", "mine");
  const auto foreign = RunDoasido({"dataset", "export", "--root", root, "--name", "pour", "v2",
                                   "--format", "lerobot", "--out", (work / "notes").string()});
  EXPECT_EQ(foreign.exit_code, 1);
  EXPECT_THAT(foreign.err, HasSubstr("unsafe_output"));  // the output guard refuses it first
  EXPECT_EQ(testing::ReadFile(work / "notes/todo.txt"), "mine");

  // One byte of an episode changed: verify fails naming the file.
  const fs::path victim = work / "datasets/pour/v2/episodes" / v2.episodes[0].id / "trajectory.json";
  {
    std::fstream f(victim, std::ios::in | std::ios::out | std::ios::binary);
    f.seekg(40);
    const char c = static_cast<char>(f.get());
    f.seekp(40);
    f.put(c == '1' ? '2' : '1');
  }
  const auto bad = RunDoasido({"dataset", "verify", "--root", root, "--name", "pour", "v2"});
  EXPECT_EQ(bad.exit_code, 1);
  EXPECT_THAT(bad.err, HasSubstr("corrupt_version"));
  EXPECT_THAT(bad.err, HasSubstr(victim.string()));
  EXPECT_EQ(RunDoasido({"dataset", "verify", "--root", root, "--name", "pour", "v1"}).exit_code, 0);
}

TEST_F(CliDataset, SplitsKeepEachVideoWholeAndListShowsVersions) {
  TempDir work;
  const std::string root = (work / "d").string();
  ASSERT_EQ(RunDoasido({"dataset", "create", "--db", Db(), "--root", root, "--select", "all",
                        "--no-thumbnails", "--split", "train=0.5,test=0.5", "--seed", "9"})
                .exit_code,
            0);
  const dataset::Manifest m = dataset::ReadManifest(work / "d/default/v1");
  std::map<std::string, std::set<std::string>> splits;
  for (const auto& e : m.episodes) splits[e.video_key].insert(e.split);
  for (const auto& [video, s] : splits) EXPECT_EQ(s.size(), 1u) << video;
  const auto list = RunDoasido({"dataset", "list", "--root", root});
  EXPECT_THAT(list.out, HasSubstr("default          v1"));
  const auto show = RunDoasido({"dataset", "show", "--root", root, "v1"});
  EXPECT_THAT(show.out, HasSubstr(m.episodes[0].id));
  const auto missing = RunDoasido({"dataset", "show", "--root", root, "v7"});
  EXPECT_EQ(missing.exit_code, 1);
  EXPECT_THAT(missing.err, HasSubstr("no_version"));
  EXPECT_THAT(missing.err, HasSubstr("default/v1"));
  const auto empty = RunDoasido({"dataset", "create", "--db", Db(), "--root", root});
  EXPECT_EQ(empty.exit_code, 1);
  EXPECT_THAT(empty.err, HasSubstr("empty_version"));
}

// Runs `dataset create` and kills it with SIGKILL after `delay`; returns
// whether it had finished first.
bool CreateAndKill(const std::vector<std::string>& args, std::chrono::microseconds delay) {
  const pid_t pid = fork();
  if (pid == 0) {
    std::vector<char*> argv;
    for (const auto& a : args) argv.push_back(const_cast<char*>(a.c_str()));
    argv.push_back(nullptr);
    freopen("/dev/null", "w", stdout);
    freopen("/dev/null", "w", stderr);
    execv(argv[0], argv.data());
    _exit(127);
  }
  std::this_thread::sleep_for(delay);
  kill(pid, SIGKILL);
  int status = 0;
  waitpid(pid, &status, 0);
  return WIFEXITED(status);
}

TEST_F(CliDataset, KilledCreateLeavesNoPartialVersion) {
  TempDir work;
  const fs::path root = work / "d";
  const std::vector<std::string> args = {testing::DoasidoBin().string(), "dataset", "create",
                                         "--db", Db(), "--root", root.string(), "--select",
                                         "all"};
  const auto t0 = std::chrono::steady_clock::now();
  ASSERT_EQ(RunDoasido({args.begin() + 1, args.end()}).exit_code, 0);
  const auto full = std::chrono::duration_cast<std::chrono::microseconds>(
      std::chrono::steady_clock::now() - t0);
  std::mt19937 rng(11);
  int killed = 0;
  for (int i = 0; i < 12; ++i) {
    const auto delay = std::chrono::microseconds(
        std::uniform_int_distribution<std::int64_t>(0, full.count())(rng));
    killed += !CreateAndKill(args, delay);
    // Whatever is listed is whole: every version verifies.
    for (const auto& v : dataset::ListVersions(root)) {
      EXPECT_TRUE(dataset::VerifyVersion(v.dir).empty()) << v.dir << " after kill " << i;
    }
  }
  std::printf("killed %d of 12 runs before they finished\n", killed);
  EXPECT_GE(killed, 10);
  const auto versions_before = dataset::ListVersions(root).size();
  ASSERT_EQ(RunDoasido({args.begin() + 1, args.end()}).exit_code, 0);
  const auto versions = dataset::ListVersions(root);
  ASSERT_EQ(versions.size(), versions_before + 1);
  EXPECT_TRUE(dataset::VerifyVersion(versions.back().dir).empty());
  for (const auto& entry : fs::directory_iterator(root / "default")) {
    EXPECT_NE(entry.path().filename().string()[0], '.') << "left behind: " << entry.path();
  }
}

// A copy of the fixture's database and artifacts in `work` (videos linked).
fs::path CopyOfTheDatabase(const fs::path& pool, const fs::path& work) {
  fs::create_directories(work);
  fs::copy_file(pool / "d.db", work / "d.db");
  fs::copy(pool / "artifacts", work / "artifacts", fs::copy_options::recursive);
  fs::create_directory_symlink(pool / "s", work / "s");
  return work / "d.db";
}

std::string Quote(const fs::path& p) { return "'" + p.string() + "'"; }

// `dataset create` of the database `db`'s clips into `root` (v1) and its robomimic
// export to `out`: the export's bytes (empty when either failed).
std::string FirstRobomimicExport(const std::string& db, const fs::path& root, const fs::path& out) {
  const auto create = RunDoasido({"dataset", "create", "--db", db, "--root",
                                  root.string(), "--select", "all", "--no-thumbnails"});
  EXPECT_EQ(create.exit_code, 0) << create.err;
  const auto first = RunDoasido({"dataset", "export", "--root", root.string(), "v1", "--format",
                                 "robomimic", "--out", out.string()});
  EXPECT_EQ(first.exit_code, 0) << first.err;
  return first.exit_code == 0 ? testing::ReadFile(out) : "";
}

// Debian's h5py opens `file` and every demo's sample count adds up to the
// file's total.
void ExpectH5pyReadsEveryDemo(const fs::path& work, const fs::path& file) {
  WriteFile(work / "read.py",
            "import h5py, sys\nd = h5py.File(sys.argv[1], 'r')['data']\n"
            "print(sum(int(d[k].attrs['num_samples']) for k in d), int(d.attrs['total']))\n");
  const std::string read =
      testing::ShellOk("/usr/bin/python3 " + Quote(work / "read.py") + " " + Quote(file));
  std::istringstream numbers(read);
  long samples = -1, total = -2;
  numbers >> samples >> total;
  EXPECT_GT(samples, 0) << read;
  EXPECT_EQ(samples, total) << read;
}

// Issue #50, finding 1: a robomimic export that does not fit on the disk
// (a tmpfs sized for one export and a little, in a private user + mount
// namespace) fails naming the file and the cause, and the earlier export is
// byte for byte what it was; with no earlier export, nothing appears.
TEST_F(CliDataset, RobomimicOnAFullDiskKeepsTheEarlierExport) {
  if (std::system("unshare -rm true 2>/dev/null") != 0) {
    GTEST_SKIP() << "user namespaces are not available on this machine";
  }
  TempDir work;
  const fs::path root = work / "datasets";
  const fs::path good = work / "good.hdf5";
  const std::string bytes = FirstRobomimicExport(Db(), root, good);
  ASSERT_GT(bytes.size(), 8192u);
  const fs::path disk = work / "disk";
  fs::create_directories(disk);
  const std::string bin = Quote(testing::DoasidoBin());
  const std::string export_args = " dataset export --root " + Quote(root) +
                                  " v1 --format robomimic --out ";
  // The disk holds the earlier export and half as much again: the marker
  // and a second copy do not fit. Then an empty disk smaller than one.
  const size_t kb = bytes.size() * 3 / 2 / 1024 + 1;
  const std::string script =
      "set -u; mount -t tmpfs -o size=" + std::to_string(kb) + "k tmpfs " + Quote(disk) +
      " || exit 90; cp " + Quote(good) + " " + Quote(disk / "x.hdf5") + " || exit 91; " + bin +
      export_args + Quote(disk / "x.hdf5") + " > " + Quote(work / "full.out") + " 2>&1; echo $? > " +
      Quote(work / "full.rc") + "; cp " + Quote(disk / "x.hdf5") + " " + Quote(work / "after.hdf5") +
      "; ls -a " + Quote(disk) + " > " + Quote(work / "full.ls") + "; umount " + Quote(disk) +
      "; mount -t tmpfs -o size=" + std::to_string(bytes.size() / 2048) + "k tmpfs " + Quote(disk) +
      " || exit 92; " + bin + export_args + Quote(disk / "y.hdf5") + " > " +
      Quote(work / "small.out") + " 2>&1; echo $? > " + Quote(work / "small.rc") + "; ls -a " +
      Quote(disk) + " > " + Quote(work / "small.ls") + "; exit 0";
  WriteFile(work / "disk.sh", script);
  ASSERT_EQ(std::system(("unshare -rm sh " + Quote(work / "disk.sh")).c_str()), 0);

  const std::string full = testing::ReadFile(work / "full.out");
  EXPECT_NE(testing::ReadFile(work / "full.rc"), "0\n") << full;
  EXPECT_THAT(full, HasSubstr("io"));
  EXPECT_THAT(full, HasSubstr("No space left on device"));
  EXPECT_THAT(full, HasSubstr("x.hdf5"));
  EXPECT_TRUE(testing::ReadFile(work / "after.hdf5") == bytes) << "the earlier export changed";
  EXPECT_EQ(testing::ReadFile(work / "full.ls"), ".\n..\nx.hdf5\n") << "temporaries left";
  const std::string small = testing::ReadFile(work / "small.out");
  EXPECT_NE(testing::ReadFile(work / "small.rc"), "0\n") << small;
  EXPECT_THAT(small, HasSubstr("No space left on device"));
  EXPECT_EQ(testing::ReadFile(work / "small.ls"), ".\n..\n") << "a failed export left a file";
  ExpectH5pyReadsEveryDemo(work.path(), work / "after.hdf5");
}

// Issue #50, finding 1 on any machine (no mount namespace needed): the
// export runs under a file-size limit (prlimit, SIGXFSZ ignored), so its
// write fails part way with EFBIG as a full disk fails with ENOSPC; the same
// promise holds: the earlier export byte for byte, nothing new, the cause
// and the file named.
TEST_F(CliDataset, RobomimicPastAFileSizeLimitKeepsTheEarlierExport) {
  TempDir work;
  const fs::path root = work / "datasets";
  const fs::path disk = work / "disk";
  fs::create_directories(disk);
  const fs::path earlier = disk / "x.hdf5";
  const std::string bytes = FirstRobomimicExport(Db(), root, earlier);
  ASSERT_GT(bytes.size(), 8192u);
  auto limited_export = [&](const fs::path& out, const std::string& name) {
    WriteFile(work / (name + ".sh"),
              "trap '' XFSZ; exec prlimit --fsize=" + std::to_string(bytes.size() / 2) + " " +
                  Quote(testing::DoasidoBin()) + " dataset export --root " + Quote(root) +
                  " v1 --format robomimic --out " + Quote(out) + " > " +
                  Quote(work / (name + ".out")) + " 2>&1");
    const int status = std::system(("sh " + Quote(work / (name + ".sh"))).c_str());
    return std::make_pair(status, testing::ReadFile(work / (name + ".out")));
  };
  const auto [replace_status, replace] = limited_export(earlier, "replace");
  EXPECT_NE(replace_status, 0) << replace;
  EXPECT_THAT(replace, HasSubstr("io"));
  EXPECT_THAT(replace, HasSubstr("File too large"));
  EXPECT_THAT(replace, HasSubstr("x.hdf5"));
  EXPECT_TRUE(testing::ReadFile(earlier) == bytes) << "the earlier export changed";
  const auto [new_status, fresh] = limited_export(disk / "y.hdf5", "new");
  EXPECT_NE(new_status, 0) << fresh;
  EXPECT_THAT(fresh, HasSubstr("File too large"));
  std::vector<std::string> left;
  for (const auto& e : fs::directory_iterator(disk)) left.push_back(e.path().filename().string());
  EXPECT_EQ(left, std::vector<std::string>{"x.hdf5"}) << "temporaries or a failed export left";
  ExpectH5pyReadsEveryDemo(work.path(), earlier);
}

// Issue #50, finding 5: `dataset create` racing a re-queue (slowed to 0.6 s
// an episode, the trajectory stage queued again meanwhile) names the race,
// the clip and the stage, and leaves no version and no temporary.
TEST_F(CliDataset, CreateRacingAReQueueNamesTheRunsThatChanged) {
  TempDir work;
  const fs::path db = CopyOfTheDatabase(dir_->path(), work / "w");
  const fs::path root = work / "datasets";
  setenv("DOASIDO_TEST_PAUSE", "version_episode=600", 1);
  const int create = testing::Spawn({testing::DoasidoBin().string(), "dataset", "create", "--db",
                                     db.string(), "--root", root.string(), "--select", "all",
                                     "--no-thumbnails"},
                                    work / "create.log");
  unsetenv("DOASIDO_TEST_PAUSE");
  // Re-queue once the version is being written (its temporary exists).
  bool writing = false;
  for (int i = 0; i < 1000 && !writing; ++i) {
    std::error_code ec;
    for (const auto& e : fs::directory_iterator(root / "default", ec)) {
      writing |= e.path().filename().string().rfind(".v1.tmp-", 0) == 0;
    }
    if (!writing) usleep(10000);
  }
  ASSERT_TRUE(writing) << testing::ReadFile(work / "create.log");
  const auto reset = RunDoasido({"queue", "reset", "--db", db.string(), "--stage",
                                 "retarget_kinematic", "--all"});
  ASSERT_EQ(reset.exit_code, 0) << reset.err;
  EXPECT_NE(testing::WaitFor(create), 0);
  const std::string log = testing::ReadFile(work / "create.log");
  EXPECT_THAT(log, HasSubstr("runs_changed"));
  EXPECT_THAT(log, HasSubstr("retarget_kinematic"));
  EXPECT_THAT(log, HasSubstr("clip "));
  EXPECT_THAT(log, ::testing::Not(HasSubstr("No such file")));
  for (const auto& e : fs::directory_iterator(root / "default")) {
    ADD_FAILURE() << "left behind: " << e.path();
  }
}

// The commands of issue #50's finding 6 on the database `db`, each run as
// the shell command `doasido`, their outputs in `out` (NAME.out/.err/.rc).
std::string ReadOnlySteps(const fs::path& db, const fs::path& out, const std::string& doasido) {
  const std::string& bin = doasido;
  auto step = [&](const std::string& name, const std::string& args) {
    return bin + " " + args + " > " + Quote(out / (name + ".out")) + " 2> " +
           Quote(out / (name + ".err")) + "; echo $? > " + Quote(out / (name + ".rc")) + "; ";
  };
  return step("status", "status --db " + Quote(db)) +
         step("report", "report --db " + Quote(db) + " --no-thumbnails --out " + Quote(out / "report")) +
         step("create", "dataset create --db " + Quote(db) + " --root " + Quote(out / "datasets") +
                            " --select all --no-thumbnails") +
         step("reset", "queue reset --db " + Quote(db) + " --stage retarget_kinematic --all");
}

// What ReadOnlySteps must show: status, report and dataset create into
// another root work and say the database is read-only; a write is refused
// with read_only naming the file.
void ExpectShownReadOnlyAndWritesRefused(const fs::path& db, const fs::path& out) {
  for (const char* name : {"status", "report", "create"}) {
    const std::string err = testing::ReadFile(out / (std::string(name) + ".err"));
    EXPECT_EQ(testing::ReadFile(out / (std::string(name) + ".rc")), "0\n") << name << ": " << err;
    EXPECT_THAT(err, HasSubstr("read-only")) << name;
  }
  EXPECT_THAT(testing::ReadFile(out / "status.out"), HasSubstr("retarget_kinematic"));
  EXPECT_TRUE(fs::exists(out / "report/report.html"));
  EXPECT_TRUE(fs::exists(out / "datasets/default/v1/manifest.json"));
  const std::string reset = testing::ReadFile(out / "reset.err");
  EXPECT_NE(testing::ReadFile(out / "reset.rc"), "0\n") << reset;
  EXPECT_THAT(reset, HasSubstr("read_only"));
  EXPECT_THAT(reset, HasSubstr(db.string()));
}

// Issue #50, finding 6: a database on a read-only mount (a bind mount in a
// private user + mount namespace: root cannot write it either) is opened
// read-only and said so; status, report and dataset create into another
// root work; a write fails with read_only naming the file.
TEST_F(CliDataset, AReadOnlyDatabaseIsShownAndRefusesWrites) {
  if (std::system("unshare -rm true 2>/dev/null") != 0) {
    GTEST_SKIP() << "user namespaces are not available on this machine";
  }
  TempDir work;
  const fs::path db = CopyOfTheDatabase(dir_->path(), work / "ro");
  const fs::path out = work / "out";
  fs::create_directories(out);
  const std::string script =
      "set -u; mount --bind " + Quote(work / "ro") + " " + Quote(work / "ro") +
      " && mount -o remount,ro,bind " + Quote(work / "ro") + " || exit 90; " +
      ReadOnlySteps(db, out, Quote(testing::DoasidoBin())) + "exit 0";
  WriteFile(work / "ro.sh", script);
  ASSERT_EQ(std::system(("unshare -rm sh " + Quote(work / "ro.sh")).c_str()), 0);
  ExpectShownReadOnlyAndWritesRefused(db, out);
}

// Finding 6 on any machine (no namespace needed): a database file and
// folder the user may not write (mode 0444 / 0555). Root writes whatever
// the mode says, so as root the commands run without the capabilities that
// override file modes (setpriv).
TEST_F(CliDataset, ADatabaseTheUserMayNotWriteIsShownAndRefusesWrites) {
  TempDir work;
  const fs::path db = CopyOfTheDatabase(dir_->path(), work / "ro");
  const fs::path out = work / "out";
  fs::create_directories(out);
  const std::string as_owner =
      geteuid() == 0 ? "setpriv --bounding-set=-dac_override,-dac_read_search "
                       "--inh-caps=-dac_override,-dac_read_search "
                     : "";
  testing::ShellOk("chmod -R a-w " + Quote(work / "ro"));
  WriteFile(work / "ro.sh", ReadOnlySteps(db, out, as_owner + Quote(testing::DoasidoBin())) + "exit 0");
  const int status = std::system(("sh " + Quote(work / "ro.sh")).c_str());
  testing::ShellOk("chmod -R u+w " + Quote(work / "ro"));
  ASSERT_EQ(status, 0);
  ExpectShownReadOnlyAndWritesRefused(db, out);
}

// Two hands through the queue into a dataset: a synthetic two-handed carry
// (pinch grasps) runs bundle -> recon -> retarget with a left robot hand,
// `dataset create` takes its two-hand trajectory, and both exports carry
// both hands' joints: robomimic's read back by h5py value for value, the
// LeRobot features named after the trajectory's joints.
TEST(CliDatasetTwoHands, ATwoHandTrajectoryBecomesAnEpisodeWithBothHands) {
  TempDir dir;
  const fs::path synth = dir / "s";
  ASSERT_EQ(RunDoasido({"synth", "--out", synth.string(), "--clips", "1", "--seed", "3", "--frames", "40",
                        "--width", "320", "--height", "240", "--mix", "clean=1", "--two-hand-task",
                        "carry", "--grasp", "pinch"}).exit_code, 0);
  WriteFile(dir / "run.toml",
            "[bundle]\ncommand = \"cp -r $(dirname $(dirname {video}))/bundles/$(basename {video} .mp4)/. "
            "{output}/\"\n[retarget]\nleft_hand = \"sharpa_left\"\npreset = \"\"\n"
            "[retarget.kinematic]\nrestarts = 1\n[retarget.sampler]\nnum_samples = 8\n"
            "max_num_iterations = 2\nhorizon = 0.2\nknot_dt = 0.1\nctrl_dt = 0.1\n");
  const std::string db = (dir / "d.db").string(), root = (dir / "datasets").string();
  ASSERT_EQ(RunDoasido({"init", "--db", db, "--pipeline", "download,probe,bundle,recon,retarget"}).exit_code, 0);
  const auto run = RunDoasido({"run", "--db", db, "--config", (dir / "run.toml").string(), synth.string()});
  ASSERT_EQ(run.exit_code, 0) << run.err;
  const auto created = RunDoasido({"dataset", "create", "--db", db, "--root", root, "--name", "two",
                                   "--select", "all"});
  ASSERT_EQ(created.exit_code, 0) << created.err;
  const dataset::Manifest v1 = dataset::ReadManifest(fs::path(root) / "two/v1");
  ASSERT_EQ(v1.episodes.size(), 1u);
  EXPECT_EQ(v1.episodes[0].embodiment, "sharpa_left+sharpa_right");
  const retarget::HandTrajectory t = retarget::ReadTrajectoryJson(
      fs::path(root) / "two/v1/episodes" / v1.episodes[0].id / "trajectory.json");
  ASSERT_EQ(t.qpos_names.size(), 56u);  // two floating wrists (6) and two 22-joint hands
  EXPECT_EQ(t.qpos_names.front().rfind("l_", 0), 0u);
  EXPECT_EQ(t.qpos_names.back().rfind("r_", 0), 0u);

  const fs::path h5 = dir / "two.hdf5";
  ASSERT_EQ(RunDoasido({"dataset", "export", "--root", root, "--name", "two", "v1", "--format", "robomimic",
                        "--out", h5.string()}).exit_code, 0);
  WriteFile(dir / "read.py", R"PY(import h5py, json, sys
d = h5py.File(sys.argv[1], 'r')['data']
g = d[list(d.keys())[0]]
print(json.dumps({'embodiment': json.loads(d.attrs['env_args'])['env_kwargs']['embodiment'],
                  'joint_pos': g['obs/robot0_joint_pos'][()].tolist()}))
)PY");
  const Json got = Json::parse(testing::ShellOk("/usr/bin/python3 " + (dir / "read.py").string() + " " + h5.string()));
  EXPECT_EQ(got["embodiment"], "sharpa_left+sharpa_right");
  ASSERT_EQ(got["joint_pos"].size(), t.qpos.size());
  for (size_t f = 0; f < t.qpos.size(); ++f) {
    ASSERT_EQ(got["joint_pos"][f].size(), 56u);
    for (size_t j = 0; j < 56; ++j) ASSERT_EQ(got["joint_pos"][f][j].get<double>(), t.qpos[f][j]) << f << " " << j;
  }

  ASSERT_EQ(RunDoasido({"dataset", "export", "--root", root, "--name", "two", "v1", "--format", "lerobot",
                        "--out", (dir / "lerobot").string()}).exit_code, 0);
  std::ifstream info_file(dir / "lerobot/meta/info.json");
  const Json info = Json::parse(info_file);
  EXPECT_EQ(info["robot_type"], "sharpa_left+sharpa_right");
  EXPECT_EQ(info["features"]["observation.state"]["names"], Json(t.qpos_names));
  EXPECT_EQ(info["features"]["action"]["shape"], Json::array({56}));
}

}  // namespace
}  // namespace doasido
