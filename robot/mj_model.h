// Owning handles for MuJoCo models and data, and compiling MJCF text.
// MuJoCo 2.2.2 (Debian) only loads MJCF from a file, so text is written to a
// private temporary file first; callers hand in self-contained XML whose
// asset paths are absolute (see mjcf_compat.h PrepareMjcf).
#pragma once

#include <memory>
#include <string>

#include <mujoco/mujoco.h>

namespace doasido::retarget {

struct MjModelDeleter {
  void operator()(mjModel* m) const { mj_deleteModel(m); }
};
struct MjDataDeleter {
  void operator()(mjData* d) const { mj_deleteData(d); }
};
using ModelPtr = std::unique_ptr<mjModel, MjModelDeleter>;
using DataPtr = std::unique_ptr<mjData, MjDataDeleter>;

// Compiles MJCF text. `label` names the source in errors. Throws
// Error("bad_mjcf", <MuJoCo's message>, {.file = label}) when MuJoCo rejects
// it. Thread-safe (each call uses its own temporary file).
ModelPtr CompileMjcfText(const std::string& xml, const std::string& label);

// mj_makeData wrapped in a handle; never null (throws Error("mujoco")).
DataPtr MakeData(const mjModel* m);

// Id of a named object or -1. `type` is an mjtObj.
int NameToId(const mjModel* m, int type, const std::string& name);

}  // namespace doasido::retarget
