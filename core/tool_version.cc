#include "core/tool_version.h"

namespace doasido {

const char* ToolVersion() { return DOASIDO_VERSION; }

}  // namespace doasido
