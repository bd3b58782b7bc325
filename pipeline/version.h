#pragma once

namespace specbake {
// The tool version recorded in every manifest.
const char* tool_version();
}  // namespace specbake
