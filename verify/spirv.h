// Run-time shader cost as SPIR-V instructions after optimisation (SPEC Sec. 8): the fragment shader is
// compiled with glslangValidator (OpenGL SPIR-V), optimised with spirv-opt -O and disassembled with
// spirv-dis; the instructions inside function bodies are counted. Needs the three tools on PATH.
#pragma once

#include "core/result.h"

#include <string>

namespace specbake::verify {

// True when glslangValidator, spirv-opt and spirv-dis are all on PATH.
bool spirv_tools_available();

// Instructions between OpFunction and OpFunctionEnd (inclusive) of the optimised module of the GLSL
// fragment shader `source`. The error carries the failing tool's output.
Result<int> spirv_instruction_count(const std::string& source);

}  // namespace specbake::verify
