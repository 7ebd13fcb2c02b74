#include "eval/hot3d_recording.h"

#include <algorithm>
#include <cmath>
#include <fstream>
#include <limits>
#include <sstream>
#include <vector>

#include "core/csv.h"
#include "core/error.h"
#include "core/hand_keypoints.h"
#include "core/json_input.h"
#include "recon/recon_metrics.h"

namespace doasido::recon {
namespace {

constexpr const char* kObjectsCsv = "dynamic_objects.csv";
constexpr const char* kHandsJsonl = "umetrack_hand_pose_trajectory.jsonl";
constexpr const char* kHandProfile = "umetrack_hand_user_profile.json";
constexpr std::array<const char*, 2> kHandKeys = {"0", "1"};  // HOT3D: 0 left, 1 right
constexpr std::array<const char*, 2> kHandNames = {"left", "right"};

std::ifstream Open(const std::filesystem::path& file) {
  std::ifstream in(file);
  if (!in) throw Error("io", "cannot read the file", {.file = file.string()});
  return in;
}

double Number(const std::string& cell, const std::filesystem::path& file, long line,
              const std::string& field) {
  try {
    size_t used = 0;
    const double v = std::stod(cell, &used);
    if (used == cell.size() && std::isfinite(v)) return v;
  } catch (const std::exception&) {
  }
  throw Error("bad_hot3d", "not a finite number: '" + cell + "'",
              {.file = file.string(), .line = line, .field = field});
}

Pose PoseFrom(const Vec3& t, const Quat& q, const std::filesystem::path& file, long line,
              const std::string& field) {
  if (!(q.norm() > 0.5 && q.norm() < 1.5)) {
    throw Error("bad_hot3d", "the quaternion is not of unit length", {.file = file.string(), .line = line, .field = field});
  }
  return {q.normalized(), t};
}

}  // namespace

std::map<std::string, std::map<long long, Pose>> ReadHot3dPoses(const std::filesystem::path& file) {
  std::map<std::string, std::map<long long, Pose>> out;
  CsvReader reader = CsvReader::Open(file, "bad_hot3d");
  const std::vector<std::string> header = reader.Header();
  static const char* kFields[] = {"object_uid", "timestamp[ns]", "t_wo_x[m]", "t_wo_y[m]", "t_wo_z[m]",
                                  "q_wo_w", "q_wo_x", "q_wo_y", "q_wo_z"};
  if (header.size() < 2 || header[0] != kFields[0] || header[1] != kFields[1]) {
    std::string names;
    for (const std::string& name : header) names += (names.empty() ? "" : ",") + name;
    reader.Fail(reader.header_line(), "",
                "not a HOT3D object pose table (header '" + names.substr(0, 60) + "')");
  }
  CsvRecord record;
  while (reader.Next(record)) {
    if (!record.error.empty()) reader.Fail(record.line, "", record.error);
    if (record.Blank()) continue;
    const std::vector<std::string>& c = record.fields;
    if (c.size() != 9) {
      reader.Fail(record.line, "", "expected 9 columns, found " + std::to_string(c.size()));
    }
    double v[9];
    for (int k = 1; k < 9; ++k) v[k] = Number(c[k], file, record.line, kFields[k]);
    out[c[0]][static_cast<long long>(v[1])] =
        PoseFrom(Vec3(v[2], v[3], v[4]), Quat(v[5], v[6], v[7], v[8]), file, record.line, "q_wo");
  }
  return out;
}

namespace {

template <int N>
Eigen::Matrix<double, N, 1> Numbers(const Json& j, const std::filesystem::path& file, long line,
                                    const std::string& field) {
  const ErrorSite site{.file = file.string(), .line = line, .field = field};
  if (!j.is_array() || j.size() != N) throw Error("bad_hot3d", "expected " + std::to_string(N) + " numbers", site);
  Eigen::Matrix<double, N, 1> v;
  for (int k = 0; k < N; ++k) {
    if (!j[k].is_number() || !std::isfinite(j[k].get<double>())) throw Error("bad_hot3d", "not a finite number", site);
    v[k] = j[k].get<double>();
  }
  return v;
}

Hot3dHandPose HandPose(const Json& j, const std::filesystem::path& file, long line) {
  Hot3dHandPose p;
  const Json x = j.value("wrist_xform", Json());
  if (!x.is_object()) {
    throw Error("bad_hot3d", "a hand pose needs wrist_xform", {.file = file.string(), .line = line, .field = "wrist_xform"});
  }
  const auto q = Numbers<4>(x.value("q_wxyz", Json()), file, line, "wrist_xform.q_wxyz");
  p.wrist = PoseFrom(Numbers<3>(x.value("t_xyz", Json()), file, line, "wrist_xform.t_xyz"),
                     Quat(q[0], q[1], q[2], q[3]), file, line, "wrist_xform.q_wxyz");
  const auto a = Numbers<kUmeTrackJoints>(j.value("joint_angles", Json()), file, line, "joint_angles");
  for (int k = 0; k < kUmeTrackJoints; ++k) p.angles[k] = a[k];
  return p;
}

void ReadHands(const std::filesystem::path& file, Hot3dRecording& rec) {
  std::ifstream in = Open(file);
  std::string row;
  for (long line = 1; std::getline(in, row); ++line) {
    if (row.empty()) continue;
    const Json j = ParseJsonInput(row, {.file = file.string(), .line = line});
    if (!j.is_object() || !j.contains("timestamp_ns") || !j["timestamp_ns"].is_number_integer() ||
        !j.contains("hand_poses") || !j["hand_poses"].is_object()) {
      throw Error("bad_hot3d", "a line needs timestamp_ns and hand_poses", {.file = file.string(), .line = line});
    }
    const long long stamp = j["timestamp_ns"].get<long long>();
    for (size_t h = 0; h < kHandKeys.size(); ++h) {
      if (j["hand_poses"].contains(kHandKeys[h])) {
        rec.hands[kHandNames[h]][stamp] = HandPose(j["hand_poses"][kHandKeys[h]], file, line);
      }
    }
  }
}

// Mean over `frames` of the distance from the nearest fingertip to the
// object's surface.
double MeanFingertipDistance(const std::vector<Joints21>& joints, const std::vector<Pose>& object,
                             const TriMesh& mesh) {
  const NearestNeighbours surface(SampleSurface(mesh, 4000, 1));
  double sum = 0;
  for (size_t t = 0; t < joints.size(); ++t) {
    const Pose inv = object[t].Inverse();
    double best = std::numeric_limits<double>::infinity();
    for (int k : kFingertips) best = std::min(best, surface.Distance(inv * Vec3(joints[t].row(k).transpose())));
    sum += best;
  }
  return sum / std::max<size_t>(1, joints.size());
}

struct Candidate {
  std::string uid;
  TriMesh mesh;
  std::vector<long long> stamps;
  std::vector<Joints21> joints;  // world
  std::vector<Pose> object;      // world
  double distance = std::numeric_limits<double>::infinity();
  bool stand_in = false;
};

// `joints`: the hand's OpenPose-21 joints per timestamp.
Candidate Pair(const Hot3dRecording& rec, const std::map<long long, Joints21>& joints,
               const std::string& uid, const TriMesh& mesh) {
  Candidate c;
  c.uid = uid;
  for (const auto& [stamp, pose] : rec.objects.at(uid)) {
    const auto it = joints.find(stamp);
    if (it == joints.end()) continue;
    c.stamps.push_back(stamp);
    c.object.push_back(pose);
    c.joints.push_back(it->second);
  }
  if (c.stamps.size() < 2) return c;
  c.mesh = mesh;
  c.distance = MeanFingertipDistance(c.joints, c.object, c.mesh);
  return c;
}

// Reflection through y = 0: points, poses and the mesh (faces reversed so
// they stay outward).
void Mirror(Reconstruction& r, TriMesh& mesh) {
  const Mat3 m = Eigen::Vector3d(1, -1, 1).asDiagonal();
  for (auto& j : r.right_joints) j = j * m;
  for (auto& j : r.left_joints) j = j * m;
  if (!r.left_valid.empty()) {  // a mirrored left hand is a right hand
    std::swap(r.right_valid, r.left_valid);
    std::swap(r.right_joints, r.left_joints);
  }
  for (auto& p : r.object_poses) p = {Quat(m * p.R() * m), m * p.t};
  mesh.vertices = mesh.vertices * m;
  for (int f = 0; f < mesh.num_faces(); ++f) std::swap(mesh.faces(f, 1), mesh.faces(f, 2));
}

}  // namespace

Hot3dRecording ReadHot3dRecording(const std::filesystem::path& dir) {
  Hot3dRecording rec;
  rec.dir = dir;
  rec.hand_model = ReadUmeTrackHand(dir / kHandProfile);
  rec.objects = ReadHot3dPoses(dir / kObjectsCsv);
  ReadHands(dir / kHandsJsonl, rec);
  return rec;
}

namespace {

// The OpenPose-21 joints of hand `name` ("left" or "right") by timestamp;
// none when the recording has no poses of it.
std::map<long long, Joints21> HandJointsByStamp(const Hot3dRecording& rec,
                                                const std::string& name) {
  std::map<long long, Joints21> out;
  const auto poses = rec.hands.find(name);
  if (poses == rec.hands.end()) return out;
  const HandSide s = name == "right" ? HandSide::kRight : HandSide::kLeft;
  for (const auto& [stamp, pose] : poses->second) {
    out[stamp] = UmeTrackOpenPose21(rec.hand_model, pose.angles, pose.wrist, s);
  }
  return out;
}

// The object the chosen hand's fingertips stay closest to (options.object_uid
// alone when set), with its model from `object_library` or the stand-in.
Candidate ClosestObject(const Hot3dRecording& rec, const std::filesystem::path& object_library,
                        const Hot3dReferenceOptions& options) {
  const std::map<long long, Joints21> joints = HandJointsByStamp(rec, options.hand);
  Candidate best;
  for (const auto& [uid, poses] : rec.objects) {
    if (!options.object_uid.empty() && uid != options.object_uid) continue;
    const auto glb = object_library / (uid + ".glb");
    const bool has_model = std::filesystem::exists(glb);
    if (!has_model && options.stand_in.num_faces() == 0) continue;
    Candidate c = Pair(rec, joints, uid, has_model ? LoadMesh(glb) : options.stand_in);
    c.stand_in = !has_model;
    if (c.distance < best.distance) best = std::move(c);
  }
  return best;
}

// The hand other than `hand` at `stamps`, moved by -origin, into the left
// hand's place of `r`, whose right hand's place holds the chosen one; then,
// when the chosen hand is the left one, the two swap to their own sides.
void AddOtherHand(const Hot3dRecording& rec, const std::string& hand,
                  const std::vector<long long>& stamps, const Vec3& origin, Reconstruction& r) {
  const std::map<long long, Joints21> other =
      HandJointsByStamp(rec, hand == "right" ? "left" : "right");
  for (const long long stamp : stamps) {
    const auto it = other.find(stamp);
    r.left_valid.push_back(it != other.end());
    r.left_joints.push_back(it != other.end() ? Joints21(it->second.rowwise() - origin.transpose())
                                              : Joints21::Zero());
  }
  if (hand == "left") {
    std::swap(r.right_valid, r.left_valid);
    std::swap(r.right_joints, r.left_joints);
  }
}

}  // namespace

Hot3dReference Hot3dToReconstruction(const Hot3dRecording& rec,
                                     const std::filesystem::path& object_library,
                                     const Hot3dReferenceOptions& options) {
  const ErrorSite site{.file = rec.dir.string(), .field = "hand"};
  if (options.hand != "left" && options.hand != "right") {
    throw Error("bad_config", "hand must be \"left\" or \"right\", not '" + options.hand + "'", site);
  }
  const auto hand = rec.hands.find(options.hand);
  if (hand == rec.hands.end() || hand->second.empty()) {
    throw Error("bad_hot3d", "the recording has no " + options.hand + " hand poses", site);
  }
  const Candidate best = ClosestObject(rec, object_library, options);
  if (best.stamps.size() < 2) {
    throw Error("bad_hot3d",
                "no object " + (options.object_uid.empty() ? std::string("with a model in ") + object_library.string()
                                                           : options.object_uid) +
                    " shares two frames with the " + options.hand + " hand",
                {.file = rec.dir.string(), .field = "object_uid"});
  }
  Hot3dReference out;
  out.object_uid = best.uid;
  out.hand = options.hand;
  out.stand_in = best.stand_in;
  out.mean_fingertip_distance = best.distance;
  out.mesh = best.mesh;
  // Reference frame: the object's frame-0 position over the origin, its
  // lowest point at frame 0 on the floor z = 0.
  const TriMesh posed = best.mesh.Transformed(best.object[0]);
  const Vec3 origin(best.object[0].t.x(), best.object[0].t.y(), posed.Min().z());
  Reconstruction& r = out.reconstruction;
  const int n = static_cast<int>(best.stamps.size());
  r.fps = 1e9 * (n - 1) / static_cast<double>(best.stamps.back() - best.stamps.front());
  r.right_valid.assign(n, true);
  r.object_valid.assign(n, true);
  for (int t = 0; t < n; ++t) {
    r.right_joints.push_back(best.joints[t].rowwise() - origin.transpose());
    r.object_poses.push_back({best.object[t].q, best.object[t].t - origin});
  }
  r.floor_z = 0;
  if (options.both_hands) AddOtherHand(rec, options.hand, best.stamps, origin, r);
  if (options.mirror) Mirror(r, out.mesh);
  out.mirrored = options.mirror;
  r.info = {{"source", "hot3d"},
            {"recording", rec.dir.string()},
            {"hand", options.hand},
            {"both_hands", options.both_hands},
            {"mirrored", options.mirror},
            {"object_uid", best.uid},
            {"object_model", best.stand_in ? "stand-in" : "hot3d"},
            {"gravity", "hot3d world, z up"},
            {"mean_fingertip_distance_m", best.distance}};
  return out;
}

}  // namespace doasido::recon
