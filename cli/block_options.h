// The command-line side of block compression (io/texture/block_compress.h, io/texture/astc_codec.h): --block, --block-rgba
// and --astc-block, shared by `texture` and `bake`.
#pragma once

#include "cli/name_options.h"
#include "core/result.h"
#include "io/texture/texture_writer.h"

#include <CLI/CLI.hpp>

#include <string>

namespace specbake::cli {

struct BlockCliOptions {
    std::string block = "none";
    std::string block_rgba = "bc1";
    std::string astc_block = "4x4";
};

// Adds the three options to `sub`; `what` names what they compress ("outputs", "baked textures").
inline void add_block_options(CLI::App& sub, BlockCliOptions& o, const std::string& what) {
    sub.add_option("--block", o.block,
                   "Block compression of the 8/16-bit " + what +
                       ", keeping every baked mip: none (default); bc (KTX2 or DDS: one channel BC4, the mean "
                       "normal BC5 with x, y only, RGBA per --block-rgba); astc (KTX2 only: ASTC LDR with the "
                       "--astc-block footprint, the mean normal x, y only). Float " + what + " stay float")
        ->check(is_member_of(io::kBlockFamilyNames))
        ->capture_default_str();
    sub.add_option("--block-rgba", o.block_rgba,
                   "BC format of four-channel " + what + " (the ORM roughness): bc1 (default; A = 1 is exact) or bc3")
        ->check(CLI::IsMember({"bc1", "bc3"}))
        ->capture_default_str();
    sub.add_option("--astc-block", o.astc_block,
                   "ASTC footprint: 4x4 (default, 8 bits a texel), 6x6 (3.56) or 8x8 (2)")
        ->check(CLI::IsMember({"4x4", "6x6", "8x8"}))
        ->capture_default_str();
}

// Fills the block fields of `format.supercompression` from `o`. When `format.container` cannot hold the
// formats asked for, the error names --block and the container option (`container_option`, e.g. "--format")
// with their values.
inline Result<void> apply_block_options(const BlockCliOptions& o, const std::string& container_option,
                                        io::TextureFileFormat& format) {
    io::Supercompression& s = format.supercompression;
    s.block = io::parse_block_family(o.block).value_or(io::BlockFamily::None);
    s.rgba_block = o.block_rgba == "bc3" ? 3 : 1;
    s.astc_block = o.astc_block == "8x8" ? 8 : o.astc_block == "6x6" ? 6 : 4;
    if (const std::string problem = io::block_container_problem(format.container, s.block); !problem.empty())
        return make_error("--block " + o.block + " with " + container_option + " " +
                          io::container_name(format.container) + ": " + problem);
    return {};
}

}  // namespace specbake::cli
