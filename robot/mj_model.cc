#include "robot/mj_model.h"

#include <unistd.h>

#include <atomic>
#include <filesystem>
#include <fstream>

#include "core/error.h"

namespace doasido::retarget {

ModelPtr CompileMjcfText(const std::string& xml, const std::string& label) {
  static std::atomic<long> counter{0};
  const std::filesystem::path tmp =
      std::filesystem::temp_directory_path() /
      ("doasido-mjcf-" + std::to_string(::getpid()) + "-" + std::to_string(counter++) + ".xml");
  {
    std::ofstream out(tmp);
    out << xml;
    if (!out) throw Error("io", "cannot write temporary MJCF", {.file = tmp.string()});
  }
  char error[1000] = "";
  mjModel* m = mj_loadXML(tmp.c_str(), nullptr, error, sizeof(error));
  std::error_code ec;
  std::filesystem::remove(tmp, ec);
  if (!m) throw Error("bad_mjcf", error[0] ? error : "MuJoCo could not compile the model",
                      {.file = label});
  return ModelPtr(m);
}

DataPtr MakeData(const mjModel* m) {
  mjData* d = mj_makeData(m);
  if (!d) throw Error("mujoco", "mj_makeData failed");
  return DataPtr(d);
}

int NameToId(const mjModel* m, int type, const std::string& name) {
  return mj_name2id(m, type, name.c_str());
}

}  // namespace doasido::retarget
