#include "pipeline/version.h"

namespace specbake {
const char* tool_version() { return SPECBAKE_VERSION; }
}  // namespace specbake
