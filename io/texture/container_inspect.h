// Reading baked textures back for inspection, independently of the writers (io/texture/ktx2.h, io/texture/dds.h,
// io/texture/block_compress.h): KTX2 and DDS are parsed here from the specifications (KTX 2.0, Khronos Data Format
// 1.3, DDS with the DX10 header or the legacy pixel formats and FourCCs specbake writes; BC1/BC3/BC4/BC5
// levels decoded by io/texture/bc_decode.h), so reading a written file is a cross-check of the writer. EXR and
// PNG go through OpenImageIO. The structural check validates a container without trusting any of its
// offsets.
#pragma once

#include "core/image.h"
#include "core/result.h"
#include "io/files/input_policy.h"
#include "io/image/inspected_texture.h"

#include <cstdint>
#include <filesystem>
#include <span>
#include <string>
#include <vector>

namespace specbake::io {

// Structure of a KTX2 or DDS file held in memory: everything a reader relies on, checked against the
// file size and against itself (KTX2: header, level index offsets/lengths/alignment and order, DFD block
// against the vkFormat, zstd levels decompressed to their exact uncompressedByteLength; DDS: magic, header sizes and flags, DX10 format and dimension, data size).
// The error names `name` and the first problem found; level 0 larger than `limits` is one.
Result<void> check_ktx2_structure(std::span<const uint8_t> bytes, const std::string& name,
                                  const InputLimits& limits = {});
Result<void> check_dds_structure(std::span<const uint8_t> bytes, const std::string& name,
                                 const InputLimits& limits = {});

// What a texture file declares: format ("ktx2", "dds", "exr", "png"), size, mip levels, channels.
// The structural check of a KTX2 or DDS file in memory (by its magic; any other content is an error), and
// the shape it declares. Reads only the headers: the level data is not touched (of a zstd level only its frame
// header, whose content size must match the level index).
Result<TextureShape> check_container_shape(std::span<const uint8_t> bytes, const std::string& name,
                                           const InputLimits& limits = {});
// The shape of an EXR, PNG or other file OpenImageIO reads, from its headers alone (every MIP level opened,
// no pixels decoded).
Result<TextureShape> read_image_shape(const std::filesystem::path& path);

// Decodes an (already checked) container in memory.
Result<InspectedTexture> decode_ktx2_for_inspection(std::span<const uint8_t> bytes, const std::string& name,
                                                    const InputLimits& limits = {});
Result<InspectedTexture> decode_dds_for_inspection(std::span<const uint8_t> bytes, const std::string& name,
                                                   const InputLimits& limits = {});

// Reads any of KTX2, DDS (by their magic), EXR (all mip levels) and PNG; KTX2 and DDS are checked first.
Result<InspectedTexture> read_texture_for_inspection(const std::filesystem::path& path,
                                                     const InputLimits& limits = {});

// Checks a KTX2 or DDS file's structure; EXR and PNG are checked by opening every mip level.
Result<void> check_texture_file(const std::filesystem::path& path, const InputLimits& limits = {});

// Writes an 8-bit RGB image as PNG, atomically.
Result<void> write_png_rgb8(const std::filesystem::path& path, int width, int height, std::span<const uint8_t> rgb);

}  // namespace specbake::io
