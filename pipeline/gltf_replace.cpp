// The glTF-valid replacement mode: UASTC KTX2 files of the baked chains written and put in the material's
// own slots (metallic-roughness layout of the roughness chain, fallback PNG, manifest entries).
#include "pipeline/gltf_replace.h"

#include "io/texture/ktx2_uastc.h"

#include "io/files/atomic_write.h"
#include "io/image/image_io.h"
#include "pipeline/uastc_encode.h"

namespace specbake {
namespace fs = std::filesystem;

namespace {

// The chain in glTF's metallic-roughness layout: G = r, B = metallic (1 when the input had none, so the
// material's metallicFactor keeps its meaning), R unused by glTF (the ORM input's occlusion, else 1).
MipChain metallic_roughness_layout(const MipChain& roughness) {
    MipChain out;
    for (const Image& l : roughness.levels) {
        Image o(l.width, l.height, 3);
        for (size_t i = 0; i < l.texel_count(); ++i) {
            const float* p = l.pixels.data() + i * size_t(l.channels);
            o.pixels[i * 3 + 0] = l.channels >= 3 ? p[0] : 1.0f;
            o.pixels[i * 3 + 1] = l.channels >= 3 ? p[1] : p[0];
            o.pixels[i * 3 + 2] = l.channels >= 3 ? p[2] : 1.0f;
        }
        out.levels.push_back(std::move(o));
    }
    return out;
}

}  // namespace

Result<io::GltfScene::BasisuTextures> replace_with_basisu(io::GltfScene& scene, const ReplaceLayer& layer,
                                                          const fs::path& basisu, const fs::path& dir, bool embed,
                                                          std::vector<io::ManifestOutput>& outputs,
                                                          std::vector<std::string>& warnings, int zstd_level) {
    const std::vector<io::MaterialInfo> materials = scene.materials();
    if (layer.material < 0 || size_t(layer.material) >= materials.size() || layer.normal.levels.empty())
        return io::GltfScene::BasisuTextures{};
    const io::MaterialInfo& mat = materials[size_t(layer.material)];
    const Image& top = layer.normal.levels.front();
    const std::string label = "material " + std::to_string(layer.material) + (mat.name.empty() ? "" : " (" + mat.name + ")");
    if (top.width % 4 != 0 || top.height % 4 != 0) {
        warnings.push_back(label + ": not replaced (--gltf-mode replace): its textures are " + std::to_string(top.width) +
                           "x" + std::to_string(top.height) + ", and KHR_texture_basisu needs sizes that are multiples of 4; "
                           "the baked textures stay in SPECBAKE_specular_aa");
        return io::GltfScene::BasisuTextures{};
    }
    io::GltfScene::BasisuTextures t;
    t.texcoord = layer.texcoord;
    t.transform = layer.transform;
    if (embed) t.embed_from = dir;
    const fs::path scratch = dir / (".basisu_" + layer.stem);
    auto write = [&](const MipChain& chain, const std::string& kind, std::string& uri) -> Result<void> {
        const std::string name = layer.stem + "_" + kind + "_basisu.ktx2";
        auto bytes = encode_uastc_ktx2(chain, basisu, scratch, name, zstd_level);
        if (!bytes) return bytes.error();
        if (auto w = io::write_file_atomic(dir / name, std::span<const uint8_t>(*bytes)); !w) return w.error();
        io::ManifestOutput o;
        o.kind = kind + "_basisu";
        o.path = name;
        o.format = "ktx2";
        o.width = chain.levels.front().width;
        o.height = chain.levels.front().height;
        o.mips = int(chain.levels.size());
        o.channels = 4;
        size_t raw = 0;  // the level bytes before zstd
        for (const Image& l : chain.levels) raw += io::uastc_level_bytes(l.width, l.height);
        o.extra = {{"gpu_format", "UASTC"}, {"supercompression", zstd_level > 0 ? "zstd" : "none"},
                   {"bytes", bytes->size()}, {"uastc_level_bytes", raw},
                   {"gltf", kind == "normal" ? "normalTexture (KHR_texture_basisu)"
                                             : "metallicRoughnessTexture (KHR_texture_basisu)"}};
        if (zstd_level > 0) o.extra["zstd_level"] = zstd_level;
        outputs.push_back(std::move(o));
        uri = name;
        return {};
    };
    // Level 0 of a baked chain as the slot's fallback source (see the header).
    auto write_fallback = [&](const Image& level0, const std::string& kind, int bits, std::string& uri) -> Result<void> {
        uri = layer.stem + "_" + kind + "_fallback.png";
        const int depth = bits > 8 ? 16 : 8;
        if (auto w = io::write_image(dir / uri, level0, depth); !w) return w.error();
        io::ManifestOutput o;
        o.kind = kind + "_fallback";
        o.path = uri;
        o.format = "png";
        o.width = level0.width;
        o.height = level0.height;
        o.mips = 1;
        o.channels = level0.channels;
        o.extra = {{"gltf", kind == "normal" ? "normalTexture source (without KHR_texture_basisu)"
                                             : "metallicRoughnessTexture source (without KHR_texture_basisu)"}};
        outputs.push_back(std::move(o));
        return {};
    };
    if (layer.normal_from) {
        t.normal_uri = layer.normal_from->normal_uri;
        t.normal_fallback_uri = layer.normal_from->normal_fallback_uri;
    } else {
        if (auto r = write(layer.normal, "normal", t.normal_uri); !r) return r.error();
        if (mat.normal.image < 0 || layer.normal_scale != 1.0)
            if (auto r = write_fallback(layer.normal.levels.front(), "normal", layer.normal_bits, t.normal_fallback_uri); !r)
                return r.error();
    }
    // A metallic-roughness texture mapped unlike the normal map was not filtered (the bake wrote no roughness),
    // and replacing it would move its metallic channel into the normal map's texture space.
    if (mat.metallic_roughness.texture >= 0 && !layer.roughness_from_texture) {
        warnings.push_back(label + ": metallicRoughnessTexture kept (--gltf-mode replace): it is mapped unlike the "
                           "normal texture, so its roughness is not replaced");
    } else if (!layer.roughness.levels.empty()) {  // empty when --outputs leaves roughness out
        const MipChain mr = metallic_roughness_layout(layer.roughness);
        if (auto r = write(mr, "roughness", t.roughness_uri); !r) return r.error();
        if (mat.metallic_roughness.image < 0 || layer.roughness_factor != 1.0)
            if (auto r = write_fallback(mr.levels.front(), "roughness", layer.roughness_bits, t.roughness_fallback_uri); !r)
                return r.error();
    }
    std::error_code ec;
    fs::remove_all(scratch, ec);
    scene.use_basisu_textures(layer.material, t);
    return t;
}

}  // namespace specbake
