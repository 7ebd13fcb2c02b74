// The bundle and recon stages end to end through the doasido binary:
// `doasido synth` clips -> a clip list -> `doasido init --pipeline
// bundle,recon` -> `doasido run` with a stand-in model command (a python3
// script written here) that copies the synthetic bundles, fails, hangs, or
// writes bad bundles. Good clips' reconstructions are read back with
// ReadReconstruction and compared with the synthetic ground truth; each bad
// clip fails with a named error (clip, file, field) while the others go on.
#include <cmath>
#include <fstream>
#include <map>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "core/config.h"
#include "db/database.h"
#include "recon/bundle/bundle.h"
#include "recon/reconstruction.h"
#include "tests/test_util.h"

namespace doasido {
namespace {

using ::testing::HasSubstr;
using doasido::testing::RunDoasido;
using doasido::testing::TempDir;
using doasido::testing::WriteFile;

constexpr const char* kModel = R"PY(import json, os, shutil, struct, sys, time, zipfile
clip, video, out = sys.argv[1], sys.argv[2], sys.argv[3]
root = os.path.dirname(os.path.dirname(video))
src = os.path.join(root, 'bundles', os.path.splitext(os.path.basename(video))[0])
if clip == 'fail':
    print('loading checkpoint', flush=True)
    print('RuntimeError: CUDA out of memory', file=sys.stderr)
    sys.exit(3)
if clip == 'hang':
    time.sleep(60)
shutil.copytree(src, out, dirs_exist_ok=True)
if clip == 'millimetres':
    meta = json.load(open(os.path.join(out, 'meta.json')))
    meta['units'] = 'mm'
    json.dump(meta, open(os.path.join(out, 'meta.json'), 'w'))
if clip == 'missing_frame':
    os.remove(os.path.join(out, 'depth', '000005.exr'))
if clip == 'empty_mask':
    open(os.path.join(out, 'masks', 'object', '000003.png'), 'wb').close()
if clip == 'nan_joints':
    path = os.path.join(out, 'hands.npz')
    arrays = {}
    with zipfile.ZipFile(path) as z:
        for n in z.namelist():
            arrays[n] = bytearray(z.read(n))
    for side in ('right', 'left'):
        key = side + '_joints.npy'
        if key not in arrays:
            continue
        valid = arrays[side + '_valid.npy']
        frame = valid[10 + struct.unpack('<H', valid[8:10])[0]:].index(1)
        raw = arrays[key]
        at = 10 + struct.unpack('<H', raw[8:10])[0] + frame * 63 * 8
        raw[at:at + 8] = struct.pack('<d', float('nan'))
        break
    with zipfile.ZipFile(path, 'w') as z:
        for n, b in arrays.items():
            z.writestr(n, bytes(b))
)PY";

Pose ReadPose(const Json& j) {
  return {Quat(j["q"][0], j["q"][1], j["q"][2], j["q"][3]).normalized(),
          Vec3(j["t"][0], j["t"][1], j["t"][2])};
}

TEST(CliRecon, SynthClipsThroughBundleAndReconStages) {
  TempDir dir;
  const auto synth = dir / "s";
  ASSERT_EQ(RunDoasido({"synth", "--out", synth.string(), "--clips", "2", "--frames", "24",
                        "--width", "320", "--height", "240", "--mix", "clean=1", "--seed", "5",
                        "--no-annotations"})
                .exit_code,
            0);
  // The synthetic clips under their own ids, and bad clips reusing the first video.
  const auto rows = doasido::testing::ReadCsv(synth / "clips.csv");
  ASSERT_EQ(rows.size(), 3u);
  std::map<std::string, std::string> video_of = {{"good0", rows[1][0]}, {"good1", rows[2][0]}};
  for (const char* bad : {"fail", "hang", "millimetres", "missing_frame", "empty_mask", "nan_joints"}) {
    video_of[bad] = rows[1][0];
  }
  // Distinct spans: the same video and span would be one clip.
  std::string list = "video,id,start_frame,end_frame\n";
  int end = 23;
  for (const auto& [id, video] : video_of) {
    list += video + "," + id + ",0," + std::to_string(end--) + "\n";
  }
  WriteFile(synth / "list.csv", list);
  WriteFile(dir / "model.py", kModel);
  WriteFile(dir / "config.toml", "[bundle]\ncommand = \"python3 " + (dir / "model.py").string() +
                                     " {clip} {video} {output}\"\ntimeout_s = 3\n");
  const std::string db = (dir / "d.db").string();
  ASSERT_EQ(RunDoasido({"init", "--db", db, "--pipeline", "bundle,recon"}).exit_code, 0);
  const auto run = RunDoasido({"run", "--db", db, "--config", (dir / "config.toml").string(),
                               "--max-attempts", "1", (synth / "list.csv").string()});
  ASSERT_EQ(run.exit_code, 0) << run.err;

  Database check(db);
  std::map<std::string, StageRunRow> bundle_runs, recon_runs;
  std::string table = run.out + run.err;
  for (const StageRunRow& r : check.ListRuns({})) {
    (r.stage == "bundle" ? bundle_runs : recon_runs)[r.external_id] = r;
    table += "\n" + r.external_id + " " + r.stage + " " + ToString(r.state) + std::string(" ") + r.error;
  }
  ASSERT_EQ(bundle_runs.size(), 8u) << table;
  const std::map<std::string, std::vector<std::string>> expected = {
      {"fail", {"bundle_command_failed", "CUDA out of memory", "field bundle.command"}},
      {"hang", {"bundle_timeout", "field bundle.command"}},
      {"millimetres", {"bad_bundle", "meta.json", "field units"}},
      {"missing_frame", {"bad_bundle", "000005.exr"}},
      {"empty_mask", {"bad_bundle", "000003.png"}},
      {"nan_joints", {"bad_bundle", "hands.npz", "_joints"}}};
  for (const auto& [clip, parts] : expected) {
    ASSERT_EQ(bundle_runs.count(clip), 1u) << clip << table;
    const StageRunRow& r = bundle_runs.at(clip);
    EXPECT_EQ(r.state, "failed") << clip;
    EXPECT_THAT(r.error, HasSubstr("clip " + clip)) << clip;
    for (const auto& p : parts) EXPECT_THAT(r.error, HasSubstr(p)) << clip;
    EXPECT_EQ(recon_runs.count(clip), 0u) << clip;
  }

  for (int i = 0; i < 2; ++i) {
    const std::string clip = "good" + std::to_string(i);
    ASSERT_EQ(recon_runs.count(clip), 1u) << clip << table;
    ASSERT_EQ(recon_runs.at(clip).state, "done") << recon_runs.at(clip).error;
    EXPECT_EQ(recon_runs.at(clip).verdict, "pass") << recon_runs.at(clip).reason;
    const recon::Reconstruction r =
        recon::ReadReconstruction(check.ArtifactDir(recon_runs.at(clip).clip_id, "recon"));
    const std::string synth_id = rows[1 + i][1];
    const recon::ClipBundle truth = recon::ReadBundle(synth / "bundles" / synth_id);
    std::ifstream gt_file(synth / "gt" / (synth_id + ".json"));
    const Json gt = Json::parse(gt_file);
    ASSERT_EQ(r.frames(), truth.frames);
    EXPECT_EQ(r.info["gravity"]["source"], "bundle_up");
    // Truth in the synthetic world: z up, table z = 0, object resting on it.
    std::vector<Pose> world;
    for (int t = 0; t < truth.frames; ++t) {
      world.push_back(ReadPose(gt["per_frame"][t]["camera_from_world"]).Inverse() *
                      truth.object_poses[t]);
    }
    int compared = 0, t0 = 0;
    while (t0 < r.frames() && !r.object_valid[t0]) ++t0;
    for (int t = t0; t < truth.frames; ++t) {
      if (!r.object_valid[t]) continue;
      ++compared;
      const Pose& p = r.object_poses[t];
      // Heights above the floor and the object's tilt are frame-independent.
      EXPECT_NEAR(p.t.z(), world[t].t.z(), 0.005) << clip << " frame " << t;
      EXPECT_NEAR((p.q * Vec3::UnitZ()).z(), (world[t].q * Vec3::UnitZ()).z(), 0.01);
      // Horizontal displacements agree up to a turn about z: compare lengths.
      const Vec3 d_rec = p.t - r.object_poses[t0].t, d_true = world[t].t - world[t0].t;
      EXPECT_NEAR(d_rec.head<2>().norm(), d_true.head<2>().norm(), 0.005) << clip << " " << t;
    }
    EXPECT_GE(compared, truth.frames * 3 / 4) << clip;
  }
}

// The track stage through the queue: bundle -> track -> recon, the bundle's
// pose candidates (flips and outliers among them) as the model; recon takes
// the tracked poses, whose heights above the table stay within 2 cm of the
// truth in most frames.
TEST(CliRecon, TrackStageBetweenBundleAndRecon) {
  TempDir dir;
  const auto synth = dir / "s";
  ASSERT_EQ(RunDoasido({"synth", "--out", synth.string(), "--clips", "2", "--frames", "24",
                        "--width", "320", "--height", "240", "--mix", "clean=1", "--seed", "5",
                        "--no-annotations"})
                .exit_code,
            0);
  WriteFile(dir / "model.py", kModel);
  WriteFile(dir / "config.toml", "[bundle]\ncommand = \"python3 " + (dir / "model.py").string() +
                                     " {clip} {video} {output}\"\n");
  const std::string db = (dir / "d.db").string();
  ASSERT_EQ(RunDoasido({"init", "--db", db, "--pipeline", "bundle,track,recon"}).exit_code, 0);
  const auto run = RunDoasido({"run", "--db", db, "--config", (dir / "config.toml").string(),
                               "--max-attempts", "1", (synth / "clips.csv").string()});
  ASSERT_EQ(run.exit_code, 0) << run.err;
  Database check(db);
  int tracked = 0;
  for (const StageRunRow& r : check.ListRuns({})) {
    EXPECT_EQ(r.state, "done") << r.external_id << " " << r.stage << " " << r.error;
    if (r.stage != "recon") continue;
    const auto track = check.GetMeasurements(r.clip_id, "track");
    ASSERT_TRUE(track.has_value());
    EXPECT_EQ((*track)["track_source"], "candidates");
    EXPECT_EQ((*track)["tracked_frames"], 24);
    EXPECT_EQ((*check.GetMeasurements(r.clip_id, "recon"))["object_pose_source"], "track");
    const recon::Reconstruction rec =
        recon::ReadReconstruction(check.ArtifactDir(r.clip_id, "recon"));
    const recon::ClipBundle truth = recon::ReadBundle(synth / "bundles" / r.external_id);
    std::ifstream gt_file(synth / "gt" / (r.external_id + ".json"));
    const Json gt = Json::parse(gt_file);
    int near = 0, valid = 0;
    for (int t = 0; t < rec.frames(); ++t) {
      if (!rec.object_valid[t]) continue;
      ++valid;
      const Pose world = ReadPose(gt["per_frame"][t]["camera_from_world"]).Inverse() *
                         truth.object_poses[t];
      near += std::abs(rec.object_poses[t].t.z() - world.t.z()) < 0.02;
    }
    EXPECT_GE(valid, 18) << r.external_id;
    EXPECT_GE(near, valid * 2 / 3) << r.external_id;
    ++tracked;
  }
  EXPECT_EQ(tracked, 2);
}

}  // namespace
}  // namespace doasido
