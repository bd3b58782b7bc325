// Writes a MipChain with its full mip chain to a texture container, atomically (temporary file + rename),
// and describes what it wrote as manifest entries (SPEC Sec. 7). Containers: KTX2 (uncompressed, see
// io/ktx2.h), DDS with the DX10 header (io/dds.h), tiled mipmapped OpenEXR (OpenImageIO, "Plain Texture"),
// or one PNG (integer encodings) / EXR (float encodings) file per mip level.
#pragma once

#include "bake/image.h"
#include "bake/result.h"
#include "bake/texture_bake.h"
#include "io/manifest.h"

#include <filesystem>
#include <optional>
#include <string>
#include <vector>

namespace specbake::io {

enum class TextureContainer { Ktx2, Dds, Exr, PngPerMip };

// How texel values are stored. Unorm: round(clamp(v, 0, 1) * (2^bits - 1)); Float16: IEEE half.
enum class TexelEncoding { Unorm8, Unorm16, Float16, Float32 };

const char* container_name(TextureContainer c);      // "ktx2", "dds", "exr", "png"
const char* encoding_name(TexelEncoding e);          // "unorm8", "unorm16", "float16", "float32"
std::optional<TextureContainer> parse_container(const std::string& name);

// Writes `chain` (1-4 channels; EXR also more) as `dir/<stem>.<ext>` (per-mip: `dir/<stem>_mip<L>.<ext>`).
// `channel_names` name the channels inside EXR files (defaults R, G, B, A). `wrap` is recorded where the
// container has a place for it (EXR "wrapmodes"). Returns one entry per file, `path` relative to `dir`,
// kind `kind`, sha256 filled. Creates `dir` when missing; the error names the file. All files of the call
// are written to temporary names first and renamed only when every one succeeded.
Result<std::vector<ManifestOutput>> write_texture(const MipChain& chain, TexelEncoding encoding,
                                                  TextureContainer container, const std::filesystem::path& dir,
                                                  const std::string& stem, const std::string& kind,
                                                  const std::vector<std::string>& channel_names = {},
                                                  WrapMode wrap = WrapMode::Repeat);

}  // namespace specbake::io
