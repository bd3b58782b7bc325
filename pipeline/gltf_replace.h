// `bake --gltf-mode replace`: the baked roughness and mean-normal chains of a material's base layer as
// KTX2 (UASTC, every baked level) in its metallicRoughnessTexture and normalTexture through
// KHR_texture_basisu, so any glTF viewer samples the filtered roughness with no shader change.
#pragma once

#include "bake/texture_bake.h"
#include "io/gltf/gltf_scene.h"
#include "io/output/manifest.h"

#include <filesystem>
#include <string>
#include <vector>

namespace specbake {

// What the replacement needs of one baked base layer.
struct ReplaceLayer {
    int material = -1;
    std::string stem;               // of the layer's baked files
    MipChain roughness;             // 1 channel r, or 3 (occlusion, r, metallic) for an ORM input
    MipChain normal;                // 3 channels, (n + 1) / 2
    bool roughness_from_texture = false;  // r came from the material's metallicRoughnessTexture
    int texcoord = 0;
    nlohmann::json transform;       // the normal texture's KHR_texture_transform, null when none
    double normal_scale = 1.0;      // normalTexture.scale, folded into `normal`
    double roughness_factor = 1.0;  // roughnessFactor, folded into `roughness`
    int normal_bits = 8, roughness_bits = 8;  // of the input images: the fallback PNGs' depth
    // The textures of an earlier layer with the same mean-normal chain: its normal KTX2 and fallback are
    // used instead of encoding the chain again.
    const io::GltfScene::BasisuTextures* normal_from = nullptr;
};

// Encodes and writes `<stem>_roughness_basisu.ktx2` and `<stem>_normal_basisu.ktx2` into `dir`, points the
// material at them (io::GltfScene::use_basisu_textures) and appends the files to `outputs` (paths relative
// to `dir`). The fallback `source` of each new texture must mean what the material now means to a viewer
// without KTX2 (normal scale and roughnessFactor are 1): the slot's old image where the folded factor is 1
// (it already means that), else `<stem>_normal_fallback.png` / `<stem>_roughness_fallback.png`, level 0 of
// the baked chain (the factor folded in) at the input's bit depth; also where the slot had no image.
// A layer whose size is not a multiple of 4 (KHR_texture_basisu) or whose metallic-roughness texture is
// mapped unlike the normal map keeps that slot, with a line in `warnings`. With `embed` (a .glb output) the
// scene carries the files on buffer views when it is written; the caller then removes them from `dir`.
// `zstd_level` 1-22 supercompresses the UASTC levels with zstd (KTX2 scheme 2), 0 leaves them plain.
// Returns the textures the material now uses (empty URIs: nothing replaced); another material with the same
// bake takes them as they are (io::GltfScene::use_basisu_textures with its own texCoord and transform), so
// the files are encoded and written once.
Result<io::GltfScene::BasisuTextures> replace_with_basisu(io::GltfScene& scene, const ReplaceLayer& layer,
                                                          const std::filesystem::path& basisu,
                                                          const std::filesystem::path& dir, bool embed,
                                                          std::vector<io::ManifestOutput>& outputs,
                                                          std::vector<std::string>& warnings, int zstd_level = 0);

}  // namespace specbake
