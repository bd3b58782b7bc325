// glTF 2.0 scenes in and out (tinygltf). A scene is loaded without decoding its images, its triangle
// primitives are read as TriMesh in their exact vertex order, baked data is added, and the scene is
// written back with everything of the input kept: nodes, transforms, materials, textures, samplers,
// animations, skins, cameras, extras and every extension. New vertex data goes into an appended buffer;
// existing buffer bytes are never rewritten (a GLB output holds them in its binary chunk, unchanged). The vendor extension is described in io/gltf/SPECBAKE_EXTENSION.md.
#pragma once

#include "core/result.h"
#include "io/files/input_policy.h"
#include "io/mesh_import/mesh_import.h"
#include "core/trimesh.h"

#include <nlohmann/json.hpp>

#include <array>
#include <cstdint>
#include <filesystem>
#include <memory>
#include <string>
#include <vector>

namespace specbake::io {

// Name of the material extension that references baked textures, and of the vertex attribute.
inline constexpr const char* kSpecbakeExtension = "SPECBAKE_specular_aa";
inline constexpr const char* kCurvatureAttribute = "_SPECAA_CURVATURE";

// One primitive of one mesh, addressed as in the glTF file.
struct PrimitiveRef {
    int mesh = 0;
    int primitive = 0;
    friend bool operator==(const PrimitiveRef&, const PrimitiveRef&) = default;
};

// What the scene says about one primitive before its vertex data is read.
struct PrimitiveInfo {
    PrimitiveRef ref;
    std::string label;       // "<file>: mesh 'Name' primitive 0", for messages
    int mode = 4;            // glTF primitive mode (4 triangles, 5 strip, 6 fan, others are not surfaces)
    int material = -1;
    bool has_normal = false;
    bool has_tangent = false;
    bool has_curvature = false;  // the input already carries _SPECAA_CURVATURE
    std::vector<int> texcoords;  // n of every TEXCOORD_n present
    // The materials KHR_materials_variants maps the primitive to (besides `material`), in file order.
    std::vector<int> variant_materials;
    // Equal for primitives that read the same vertex and index data (same accessors and mode), which
    // then share one curvature and one appended accessor.
    std::string geometry_key;
    // Largest and smallest axis scale of the world transforms of the nodes that instance the mesh
    // (1 when no node does); curvature is stored in object space and these say how far world space differs.
    double min_instance_scale = 1.0;
    double max_instance_scale = 1.0;
    int instances = 0;
};

// A texture slot of a material: the image it samples and its UV mapping, uv' = T(offset) R(rotation)
// S(scale) TEXCOORD_texcoord (KHR_texture_transform, whose texCoord overrides the slot's; its defaults when
// a value or the extension is absent).
struct TextureSlot {
    int texture = -1;  // glTF texture index, -1 when the slot is empty
    int image = -1;    // glTF image index, -1 when the texture has no (decodable) source
    int texcoord = 0;
    bool transformed = false;  // KHR_texture_transform on the slot
    nlohmann::json transform;  // that extension object, null when absent
    std::array<double, 2> offset{0.0, 0.0};
    double rotation = 0.0;     // radians, counter-clockwise
    std::array<double, 2> scale{1.0, 1.0};
};

// Whether two slots sample their images at the same UV for every vertex: the same TEXCOORD set and the same
// transform (values equal to 1e-6 relative, so float round trips of one authored value compare equal). Two
// slots with a transform each that is the same tiling are aligned; the presence of the extension is not the
// test.
bool same_uv_mapping(const TextureSlot& a, const TextureSlot& b);
// The mapping for messages: "TEXCOORD_1", or "TEXCOORD_0 offset (0.5, 0) rotation 0 scale (4, 4)".
std::string uv_mapping_label(const TextureSlot& slot);
// The transform as the baked textures' KHR_texture_transform (offset, rotation, scale, every value
// written), null when it is the identity.
nlohmann::json uv_transform_json(const TextureSlot& slot);

// KHR_materials_clearcoat of a material: the coat's own normal texture and roughness.
struct ClearcoatInfo {
    bool present = false;          // the material has the extension
    double factor = 0.0;           // clearcoatFactor
    TextureSlot factor_texture;    // clearcoatTexture (R)
    TextureSlot normal;            // clearcoatNormalTexture; empty: the coat uses the geometry normal
    double normal_scale = 1.0;
    TextureSlot roughness;         // clearcoatRoughnessTexture (roughness in G)
    double roughness_factor = 0.0; // clearcoatRoughnessFactor
    // The coat exists: the extension is there and its factor is not 0 everywhere.
    bool active() const { return present && (factor > 0.0 || factor_texture.texture >= 0); }
};

struct MaterialInfo {
    std::string name;
    TextureSlot normal;
    double normal_scale = 1.0;
    TextureSlot metallic_roughness;  // roughness in G, metallic in B (glTF)
    double roughness_factor = 1.0;
    double metallic_factor = 1.0;
    ClearcoatInfo clearcoat;
    nlohmann::json glints;  // the SPECBAKE_glints object (io/gltf/glint_extension.h), null when absent
};

class GltfScene {
public:
    GltfScene();
    ~GltfScene();
    GltfScene(GltfScene&&) noexcept;
    GltfScene& operator=(GltfScene&&) noexcept;

    // Loads a .gltf or .glb file. Images are not decoded; their bytes and URIs are kept as they are.
    // Refused before or right after parsing, with the file named: JSON deeper or larger than the limits,
    // URIs the path policy refuses (io/files/input_policy.h), more nodes or primitives than the limits, a node
    // hierarchy with a cycle. The accessors read later are held to the same limits.
    static Result<GltfScene> load(const std::filesystem::path& path, const InputPolicy& policy = {});
    // A new scene from an Assimp import (io/mesh_import/mesh_import.h): one glTF mesh with one triangle primitive per
    // imported mesh (positions, normals, tangents, TEXCOORD_0, indices as given), the node hierarchy with
    // its matrices, and one material per imported material: its name and, when the file states one, its
    // roughness (metallicFactor 0: these formats describe dielectrics unless they say otherwise).
    static Result<GltfScene> from_imported(const ImportedScene& imported);

    const std::filesystem::path& source() const;
    bool source_is_binary() const;
    // The files the scene reads besides itself: external buffers and images that exist on disk, each at the
    // one path the path policy resolved its URI to (io/files/input_policy.h); the same paths are read and copied.
    // For a scene built from an import: the files Assimp read besides the asset (an OBJ's .mtl).
    std::vector<std::filesystem::path> resource_files() const;
    // SHA-256 of the scene file or of an external buffer, computed from the bytes read at load time (the
    // scene file's in the background after load() returns; the first call waits for it); empty for any
    // other file (images are not read at load) and for scenes built from an import.
    std::string content_hash(const std::filesystem::path& file) const;

    std::vector<PrimitiveInfo> primitives() const;
    std::vector<MaterialInfo> materials() const;

    // Reads a primitive as TriMesh: every accessor type, normalisation, stride and sparse substitution
    // resolved to float/uint32, vertices in file order, strips and fans expanded to triangle lists.
    // TriMesh::uv0 holds TEXCOORD_<uv_set> (the set generated tangents follow: the normal texture's).
    // The error names the file, mesh and primitive and the problem (index out of range, bad accessor ...).
    Result<TriMesh> primitive_mesh(PrimitiveRef ref, int uv_set = 0) const;

    // The encoded bytes of an image (external file, data URI or buffer view), as stored.
    Result<std::vector<uint8_t>> image_bytes(int image) const;
    std::string image_label(int image) const;  // URI or "<file>: image N", for messages
    // The file of an image stored as an external file, empty for embedded images.
    std::filesystem::path image_file(int image) const;

    // Baked additions, applied by write(): a float attribute with `components` values per vertex in the
    // primitive's vertex order (_SPECAA_CURVATURE: 4, TANGENT: 4, NORMAL: 3). The primitive then refers to
    // a new accessor in the appended buffer; the accessor it referred to before keeps its bytes.
    Result<void> set_vertex_attribute(PrimitiveRef ref, const std::string& attribute, std::vector<float> values,
                                      int components);
    // Sets the vendor extension object on a material (replacing an earlier one) and lists the extension
    // in extensionsUsed (never extensionsRequired).
    void set_material_extension(int material, const nlohmann::json& extension);
    // glTF-valid replacement (`bake --gltf-mode replace`): the material's normalTexture and
    // metallicRoughnessTexture become new textures whose KHR_texture_basisu source is the given KTX2 file
    // (UASTC), with a fallback `source` (`*_fallback_uri` as PNG, or the texture's old image when empty), a trilinear
    // sampler (the old sampler's wrapping), the baked textures' texCoord and transform; normal scale and
    // roughnessFactor become 1 (the bake applied them). An empty URI leaves that slot alone.
    struct BasisuTextures {
        std::string normal_uri, roughness_uri;
        std::string normal_fallback_uri, roughness_fallback_uri;  // empty: the slot's old image is the fallback
        int texcoord = 0;
        nlohmann::json transform;  // KHR_texture_transform of the baked textures, null when none
        // For a .glb output: the folder holding the files the URIs name. They then go on buffer views of the
        // binary chunk when the scene is written (image/ktx2, image/png), as the input's images do.
        std::filesystem::path embed_from;
    };
    void use_basisu_textures(int material, const BasisuTextures& textures);
    // Sets the vendor extension object at the root of the glTF (tool version, settings).
    void set_root_extension(const nlohmann::json& extension);
    // A file the bake wrote (a KTX2, DDS or PNG texture) carried inside a .glb output, on a buffer view of
    // the binary chunk named `name`. Returns its number k (the same file asked twice: one view); an object
    // in a SPECBAKE_specular_aa "outputs" array that holds "embedded": k gets "bufferView": <that view> in
    // its place when a GLB is written. Not glTF images: glTF allows image/ktx2 only for Basis Universal
    // data (KHR_texture_basisu) and no DDS without MSFT_texture_dds, so the validator would flag them.
    // A .gltf output ignores it (the file stays beside the scene).
    int embed_baked_image(const std::filesystem::path& file, const std::string& mime_type, const std::string& name);

    struct WrittenFile {
        std::filesystem::path path;
        std::string sha256;  // of the bytes written, hashed while writing
        // A copied image whose own name was taken (by a file the bake writes or another copy): that name.
        std::string renamed_from;
    };
    // Writes the scene to `path`. A .gltf gets its buffers as files beside it (the input's, plus one for
    // the appended data) and copies of its external images, so the folder is self-contained. A .glb is
    // self-contained by itself: every buffer, every external image (PNG, JPEG, KTX2, WebP, DDS) and the
    // appended data go into its binary chunk as buffer views; data-URI images stay as they are. All files
    // go to temporaries first and are renamed into place together. Returns the written files, scene first.
    // No buffer or copied image takes a name in `reserved` (relative to the output folder: the files the
    // caller writes there), the scene's, or another copy's: it is renamed NAME_1.EXT, NAME_2.EXT, ...
    Result<std::vector<WrittenFile>> write(const std::filesystem::path& path,
                                           const std::vector<std::string>& reserved = {}) const;

private:
    struct Impl;
    std::unique_ptr<Impl> impl_;
};

}  // namespace specbake::io
