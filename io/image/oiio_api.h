// The OpenImageIO half of io/: image decoding, the integer image writers and the EXR/PNG reader of
// `inspect`, built as a module of its own (libspecbake_oiio.so, source io/image/oiio_module.cpp) that is
// loaded on first use. OpenImageIO pulls in some 250 shared libraries, and binding them costs about
// 0.25 s at every process start; commands that never pass an image through it (scene bakes without
// textures, `mesh`, `plan`, `shader`, `inspect` of KTX2 and DDS files, `--help`) no longer pay that.
//
// Where the module is looked for, first found wins: $SPECBAKE_OIIO_MODULE (exactly that file), then
// beside the running executable, then <bindir>/../<libdir>/specbake/ relative to it (the installed
// layout), then the install prefix configured at build time, then the build tree.
#pragma once

#include "core/image.h"
#include "core/result.h"
#include "io/image/inspected_texture.h"
#include "io/image/image_io.h"

#include <cstdint>
#include <span>
#include <string>
#include <vector>

namespace specbake::io::oiio {

enum class PixelType { Uint8, Uint16, Half, Float };

// The module's entry points. Every error names the file.
struct Api {
    uint32_t size;    // sizeof(Api) of the build the module belongs to
    const char* tag;  // that build's version and interface number; must equal the caller's
    // First subimage, level 0, as float; `name` is the path (decode_file) or the label used in errors.
    // An image whose header claims more than `max_texels` texels is refused before its pixels are read.
    Result<DecodedImage> (*decode_file)(const std::string& name, uint64_t max_texels);
    // `probe`: a file name whose extension selects the decoder ("image.png").
    Result<DecodedImage> (*decode_memory)(std::span<const uint8_t> bytes, const std::string& probe,
                                          const std::string& name, uint64_t max_texels);
    // An 8- or 16-bit integer file, the format from name's extension, values clamped to [0, 1].
    Result<void> (*write_image)(const std::string& temp_path, const std::string& name, const Image& image,
                                PixelType type);
    // Every MIP level of an EXR, PNG or other file OpenImageIO reads, for `inspect`; channel_names from
    // the "specbake:channels" attribute where the file has it.
    Result<InspectedTexture> (*read_levels)(const std::string& name, uint64_t max_texels);
    Result<void> (*write_rgb8)(const std::string& temp_path, const std::string& name, int width, int height,
                               const uint8_t* rgb);
    // Format, size, levels and channels from the headers of every MIP level, no pixels (`inspect --check`).
    Result<TextureShape> (*read_shape)(const std::string& name);
};

// The module's entry points, loaded once (thread-safe); the error says which files were tried and why
// each failed.
Result<const Api*> api();

}  // namespace specbake::io::oiio

// The module's one exported symbol.
extern "C" const specbake::io::oiio::Api* specbake_oiio_api();
