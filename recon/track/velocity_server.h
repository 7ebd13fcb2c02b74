// A velocity field answered by another process (recon/track/velocity_field.h):
// how a user plugs in SAM 3D or any flow-matching object model that runs in
// Python. doasido starts the server command (through /bin/sh, in its own
// process group) and talks to it over the child's stdin and stdout; the
// server's stderr goes to a log file.
//
// Protocol (version kVelocityProtocol). Every message is a frame:
//   u32 little-endian header length, header (UTF-8 JSON object),
//   u32 little-endian payload length, payload (raw little-endian float64,
//   C order; may be empty).
// doasido sends, in order:
//   {"type": "hello", "protocol": 1}
//     -> {"type": "hello", "protocol": 1, "shape_dim": S, "pose_dim": 7,
//         "frames": F, "divergence": true|false}
//   {"type": "velocity", "frame": k, "t": t, "rows": N, "cols": S + 7} + N x D states
//     -> {"type": "velocity", "rows": N, "cols": D} + N x D velocities
//   {"type": "divergence", ...same...} + N x D states
//     -> {"type": "divergence", "rows": N, "cols": 1} + N values of
//        tr(d v_pose / d x_pose), the pose block's exact divergence
//   {"type": "bye"}   (no answer; the server exits)
// A server that cannot answer replies {"type": "error", "message": "..."}.
// The pose block is t xyz (metres, OpenCV camera frame) then quaternion wxyz
// of the object-to-camera transform; a SAM 3D wrapper converts SAM 3D's
// PyTorch3D frame and row-vector quaternion both ways (REFERENCE.md), runs
// the flow network on the frame's image and mask for `velocity`, and
// answers `divergence` with one vector-Jacobian product per pose
// coordinate (or says "divergence": false: likelihood ranking is then
// unavailable, clustering works). tools/velocity_server.py is a working
// reference with the Gaussian-mixture stand-in.
//
// Errors (doasido::Error codes), each naming the command and the log:
//   model_server_died      the server exited or closed its pipes (with its
//                          exit status and the tail of its log)
//   model_server_protocol  a frame that is not one: bad lengths, JSON,
//                          type, shape or non-finite numbers
//   model_server_version   the hello names another protocol version
//   model_server_error     the server answered {"type": "error"}
#pragma once

#include <filesystem>
#include <string>
#include <sys/types.h>

#include "core/config.h"
#include "recon/track/velocity_field.h"

namespace doasido::recon {

inline constexpr int kVelocityProtocol = 1;
inline constexpr const char* kServerDied = "model_server_died";
inline constexpr const char* kServerProtocol = "model_server_protocol";
inline constexpr const char* kServerVersion = "model_server_version";
inline constexpr const char* kServerError = "model_server_error";

class VelocityServer : public VelocityField {
 public:
  // Starts `command` and says hello. `log` receives the server's stderr.
  VelocityServer(const std::string& command, const std::filesystem::path& log);
  ~VelocityServer() override;  // says bye, then ends the process group
  VelocityServer(const VelocityServer&) = delete;
  VelocityServer& operator=(const VelocityServer&) = delete;

  FlowLayout Layout() const override { return layout_; }
  int frames() const { return frames_; }
  void Velocity(int frame, double t, const StateMatrix& x, StateMatrix* v) override;
  void PoseDivergence(int frame, double t, const StateMatrix& x, Eigen::VectorXd* div) override;

 private:
  // Sends one frame; reads one answer of `type` with `cols` columns.
  StateMatrix Ask(const Json& header, const StateMatrix* payload, const std::string& type,
                  Eigen::Index rows, Eigen::Index cols);
  void Send(const Json& header, const StateMatrix* payload);
  Json Receive(std::vector<double>* payload);
  [[noreturn]] void Fail(const std::string& code, const std::string& message);

  std::string command_;
  std::filesystem::path log_;
  pid_t pid_ = -1;
  int to_server_ = -1;
  int from_server_ = -1;
  FlowLayout layout_;
  int frames_ = 0;
  bool divergence_ = false;
};

}  // namespace doasido::recon
