#include "dataset/robomimic_export.h"

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <map>
#include <vector>

#include <hdf5.h>

#include "core/error.h"
#include "dataset/trajectory_uniformity.h"
#include "dataset/version.h"
#include "robot/trajectory/format.h"

namespace doasido::dataset {
namespace {

namespace fs = std::filesystem;

// An HDF5 handle closed by `close` when it goes out of scope.
class Handle {
 public:
  Handle(hid_t id, herr_t (*close)(hid_t), const std::string& what, const fs::path& file)
      : id_(id), close_(close) {
    if (id_ < 0) throw Error("io", "HDF5 cannot create " + what, {.file = file.string()});
  }
  ~Handle() {
    if (id_ >= 0) close_(id_);
  }
  // Closes now; false when HDF5 says it could not.
  bool Close() {
    const herr_t status = close_(id_);
    id_ = -1;
    return status >= 0;
  }
  Handle(const Handle&) = delete;
  Handle& operator=(const Handle&) = delete;
  hid_t get() const { return id_; }

 private:
  hid_t id_;
  herr_t (*close_)(hid_t);
};

struct Writer {
  fs::path file;

  Handle Group(hid_t parent, const std::string& name) const {
    return Handle(H5Gcreate2(parent, name.c_str(), H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT),
                  H5Gclose, "group " + name, file);
  }
  // A (rows, cols) dataset, or (rows) when cols is 0.
  template <typename T>
  void Data(hid_t parent, const std::string& name, const std::vector<T>& values, hsize_t rows,
            hsize_t cols) const {
    const hsize_t dims[2] = {rows, cols};
    Handle space(H5Screate_simple(cols ? 2 : 1, dims, nullptr), H5Sclose, "space " + name, file);
    const hid_t type = std::is_same_v<T, double> ? H5T_NATIVE_DOUBLE : H5T_NATIVE_INT64;
    Handle set(H5Dcreate2(parent, name.c_str(), type, space.get(), H5P_DEFAULT, H5P_DEFAULT,
                          H5P_DEFAULT),
               H5Dclose, "dataset " + name, file);
    Check(H5Dwrite(set.get(), type, H5S_ALL, H5S_ALL, H5P_DEFAULT, values.data()),
          "dataset " + name);
  }
  void Attr(hid_t parent, const std::string& name, std::int64_t value) const {
    Handle space(H5Screate(H5S_SCALAR), H5Sclose, "space", file);
    Handle attr(H5Acreate2(parent, name.c_str(), H5T_NATIVE_INT64, space.get(), H5P_DEFAULT,
                           H5P_DEFAULT),
                H5Aclose, "attribute " + name, file);
    Check(H5Awrite(attr.get(), H5T_NATIVE_INT64, &value), "attribute " + name);
  }
  // Every HDF5 call's result is checked: a failed one is an io error
  // naming the file and what was being written, never a half file.
  void Check(herr_t status, const std::string& what) const {
    if (status < 0) throw Error("io", "HDF5 cannot write " + what, {.file = file.string()});
  }
  // Fixed-length strings: what h5py reads back as bytes objects, robomimic's format.
  void Strings(hid_t parent, const std::string& name, const std::vector<std::string>& values,
               bool scalar_attr) const {
    size_t width = 1;
    for (const std::string& v : values) width = std::max(width, v.size());
    Handle type(H5Tcopy(H5T_C_S1), H5Tclose, "string type", file);
    Check(H5Tset_size(type.get(), width), "string type of " + name);
    std::vector<char> packed(width * std::max<size_t>(values.size(), 1), '\0');
    for (size_t i = 0; i < values.size(); ++i) values[i].copy(packed.data() + i * width, width);
    const hsize_t n = values.size();
    Handle space(scalar_attr ? H5Screate(H5S_SCALAR) : H5Screate_simple(1, &n, nullptr),
                 H5Sclose, "space " + name, file);
    if (scalar_attr) {
      Handle attr(H5Acreate2(parent, name.c_str(), type.get(), space.get(), H5P_DEFAULT,
                             H5P_DEFAULT),
                  H5Aclose, "attribute " + name, file);
      Check(H5Awrite(attr.get(), type.get(), packed.data()), "attribute " + name);
    } else {
      Handle set(H5Dcreate2(parent, name.c_str(), type.get(), space.get(), H5P_DEFAULT,
                            H5P_DEFAULT, H5P_DEFAULT),
                 H5Dclose, "dataset " + name, file);
      if (n) {
        Check(H5Dwrite(set.get(), type.get(), H5S_ALL, H5S_ALL, H5P_DEFAULT, packed.data()),
              "dataset " + name);
      }
    }
  }
};

// Rows of one observation or action, frame by frame.
using Rows = std::vector<std::vector<double>>;

std::vector<double> Flatten(const Rows& rows, size_t from) {
  std::vector<double> out;
  for (size_t i = 0; i < rows.size(); ++i) {
    const auto& r = rows[std::min(i + from, rows.size() - 1)];
    out.insert(out.end(), r.begin(), r.end());
  }
  return out;
}

std::map<std::string, Rows> Observations(const retarget::HandTrajectory& t) {
  std::map<std::string, Rows> obs;
  for (size_t f = 0; f < t.qpos.size(); ++f) {
    obs["robot0_joint_pos"].emplace_back(t.qpos[f].data(), t.qpos[f].data() + t.qpos[f].size());
    if (!t.object_poses.empty()) {
      const Pose& p = t.object_poses[f];
      obs["object"].push_back({p.t.x(), p.t.y(), p.t.z(), p.q.w(), p.q.x(), p.q.y(), p.q.z()});
    }
    if (!t.reference_keypoints.empty()) {
      const auto& k = t.reference_keypoints[f];
      std::vector<double> row;
      for (int i = 0; i < 21; ++i) {
        for (int c = 0; c < 3; ++c) row.push_back(k(i, c));
      }
      obs["hand_keypoints"].push_back(row);
    }
  }
  return obs;
}

void WriteDemo(const Writer& w, hid_t data, const Episode& e, const retarget::HandTrajectory& t) {
  const hsize_t n = t.qpos.size();
  Handle demo = w.Group(data, "demo_" + std::to_string(e.index));
  w.Attr(demo.get(), "num_samples", static_cast<std::int64_t>(n));
  w.Attr(demo.get(), "clip_id", e.clip_id);
  w.Attr(demo.get(), "hand_only", static_cast<std::int64_t>(e.hand_only));
  w.Strings(demo.get(), "episode_id", {e.id}, true);
  const std::map<std::string, Rows> obs = Observations(t);
  Rows actions;
  for (size_t f = 0; f < n; ++f) {
    const Eigen::VectorXd& a = t.ctrl.empty() ? t.qpos[std::min<size_t>(f + 1, n - 1)] : t.ctrl[f];
    actions.emplace_back(a.data(), a.data() + a.size());
  }
  Rows states = obs.at("robot0_joint_pos");
  if (obs.count("object")) {
    for (size_t f = 0; f < n; ++f) {
      states[f].insert(states[f].end(), obs.at("object")[f].begin(), obs.at("object")[f].end());
    }
  }
  w.Data(demo.get(), "actions", Flatten(actions, 0), n, actions[0].size());
  w.Data(demo.get(), "states", Flatten(states, 0), n, states[0].size());
  std::vector<double> rewards(n, 0.0);
  std::vector<std::int64_t> dones(n, 0);
  rewards.back() = 1;
  dones.back() = 1;
  w.Data(demo.get(), "rewards", rewards, n, 0);
  w.Data(demo.get(), "dones", dones, n, 0);
  for (const auto& [group, from] : {std::pair<const char*, size_t>{"obs", 0}, {"next_obs", 1}}) {
    Handle g = w.Group(demo.get(), group);
    for (const auto& [key, rows] : obs) w.Data(g.get(), key, Flatten(rows, from), n, rows[0].size());
  }
}

// Writes `bytes` to `path`, every write and the close checked (a full
// disk is an io error naming the file and the cause).
void WriteBytes(const fs::path& path, const std::vector<char>& bytes) {
  std::error_code ec;
  if (path.has_parent_path()) fs::create_directories(path.parent_path(), ec);
  std::FILE* f = std::fopen(path.c_str(), "wb");
  const bool written = f != nullptr && std::fwrite(bytes.data(), 1, bytes.size(), f) == bytes.size();
  const int saved = errno;
  const bool closed = f != nullptr && std::fclose(f) == 0;
  if (!written || !closed) {
    throw Error("io", std::string("cannot write the HDF5 file: ") +
                          std::strerror(written ? errno : saved),
                {.file = path.string()});
  }
}

}  // namespace

ExportSummary ExportRobomimic(const fs::path& version_dir, const fs::path& out_file) {
  const Manifest m = ReadManifest(version_dir);
  // Every trajectory is read and compared before the file is touched: a
  // version that mixes robots or features is refused, not half written.
  std::vector<retarget::HandTrajectory> trajectories;
  for (const Episode& e : m.episodes) {
    const fs::path path = version_dir / kEpisodesFolder / e.id / kTrajectoryFile;
    trajectories.push_back(retarget::ReadTrajectoryJson(path));
    const retarget::HandTrajectory& t = trajectories.back();
    if (t.qpos.empty()) {
      throw Error("bad_trajectory", "the trajectory has no frames",
                  {.clip = e.external_id, .file = path.string(), .field = "qpos"});
    }
    const Mismatch mixed = TrajectoryMismatch(t, trajectories.front(), m.episodes.front().external_id);
    if (!mixed.field.empty()) {
      throw Error(kMixedTrajectories,
                  mixed.why + " (a robomimic file holds one robot and one set of observations)",
                  {.clip = e.external_id, .file = path.string(), .field = mixed.field});
    }
  }
  H5Eset_auto2(H5E_DEFAULT, nullptr, nullptr);  // errors become our Error, not stderr noise
  // The file is built in memory (HDF5's core driver) and written out by us:
  // HDF5 reports a full disk at neither flush nor close (both return
  // success over a file it could not write), so its own disk writes could
  // leave a truncated file that looks finished. Our write checks every byte.
  Handle fapl(H5Pcreate(H5P_FILE_ACCESS), H5Pclose, "file access properties", out_file);
  if (H5Pset_fapl_core(fapl.get(), 1 << 20, /*backing_store=*/0) < 0) {
    throw Error("io", "HDF5 cannot use its in-memory driver", {.file = out_file.string()});
  }
  Handle file(H5Fcreate(out_file.c_str(), H5F_ACC_TRUNC, H5P_DEFAULT, fapl.get()), H5Fclose,
              "the file", out_file);
  const Writer w{out_file};
  Handle data = w.Group(file.get(), "data");
  ExportSummary summary;
  std::map<std::string, std::vector<std::string>> masks;
  std::string embodiment;
  for (size_t i = 0; i < m.episodes.size(); ++i) {
    const Episode& e = m.episodes[i];
    const retarget::HandTrajectory& t = trajectories[i];
    WriteDemo(w, data.get(), e, t);
    masks[e.split].push_back("demo_" + std::to_string(e.index));
    summary.frames += static_cast<std::int64_t>(t.qpos.size());
    embodiment = t.embodiment;
  }
  summary.episodes = static_cast<std::int64_t>(m.episodes.size());
  w.Attr(data.get(), "total", summary.frames);
  // Not an environment robomimic can build: the scene is the version's MJCF.
  const Json env_args = {{"env_name", "doasido/" + embodiment},
                         {"type", nullptr},
                         {"env_kwargs",
                          {{"embodiment", embodiment},
                           {"dataset", m.name + "/" + m.version},
                           {"trajectory_stage", m.trajectory_stage},
                           {"scene", "episodes/<episode>/" + m.trajectory_stage + "/robot_scene.xml"}}}};
  w.Strings(data.get(), "env_args", {env_args.dump()}, true);
  Handle mask = w.Group(file.get(), "mask");
  for (const auto& [split, demos] : masks) w.Strings(mask.get(), split, demos, false);
  mask.Close();
  data.Close();
  w.Check(H5Fflush(file.get(), H5F_SCOPE_GLOBAL), "the file");
  const ssize_t size = H5Fget_file_image(file.get(), nullptr, 0);
  std::vector<char> image(size > 0 ? static_cast<size_t>(size) : 0);
  if (size <= 0 || H5Fget_file_image(file.get(), image.data(), image.size()) != size) {
    throw Error("io", "HDF5 cannot give the file's bytes", {.file = out_file.string()});
  }
  if (!file.Close()) throw Error("io", "HDF5 cannot close the file", {.file = out_file.string()});
  WriteBytes(out_file, image);
  summary.bytes = static_cast<std::int64_t>(image.size());
  return summary;
}

}  // namespace doasido::dataset
