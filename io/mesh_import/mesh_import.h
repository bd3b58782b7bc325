// import_mesh: any Assimp-readable mesh file (glTF/GLB, FBX, OBJ, PLY, DAE, STL, ...) as TriMesh
// primitives, plus the material facts the bake plan needs and the node hierarchy for writing glTF.
#pragma once

#include <array>
#include <filesystem>
#include <string>
#include <vector>

#include "core/result.h"
#include "core/trimesh.h"
#include "io/files/input_policy.h"

namespace specbake {

struct ImportedMaterial {
    std::string name;
    bool has_normal_texture = false;
    std::string normal_texture;       // as referenced by the file ("*N" = embedded texture N); empty when none
    bool has_roughness_texture = false;
    std::string roughness_texture;    // glTF: the metallicRoughness texture (roughness in G)
    // The files of those references, resolved by the path policy (io/files/input_policy.h) relative to the
    // asset's folder; empty for embedded textures.
    std::filesystem::path normal_texture_file, roughness_texture_file;
    // Perceptual roughness r (SPEC Sec. 2). glTF: roughnessFactor; other formats: the file's roughness
    // when it has one, else from the Phong exponent Ns as r = (2 / (Ns + 2))^(1/4) (Beckmann-Phong match);
    // 1 when the file says nothing.
    float roughness_factor = 1.0f;
    bool roughness_from_file = false;  // false when roughness_factor is the default or derived from Ns
};

struct ImportedNode {
    std::string name;
    int parent = -1;                        // index into ImportedScene::nodes, -1 for the root
    std::array<float, 16> local_transform;  // column-major 4x4 (glTF "matrix" layout)
    std::vector<int> meshes;                // indices into ImportedScene::meshes
};

struct ImportedScene {
    std::string path;
    std::vector<TriMesh> meshes;               // one per Assimp mesh (= glTF primitive), object space as authored
    std::vector<ImportedMaterial> materials;   // TriMesh::material indexes this
    std::vector<ImportedNode> nodes;           // nodes[0] is the root
    std::vector<std::string> notes;            // what was dropped or changed on the way in (points/lines, ...)
    std::vector<std::filesystem::path> files;  // the files Assimp read besides `path` (an OBJ's .mtl, ...)
};

enum class VertexJoin {
    Auto,    // join identical vertices except for glTF/GLB (whose vertex order must match the file)
    Always,  // Assimp JoinIdenticalVertices: indexed output from soups (STL, OBJ)
    Never,   // vertex order exactly as Assimp delivers it
};

struct MeshImportOptions {
    VertexJoin join = VertexJoin::Auto;
};

// Reads `path` with Assimp: triangulates polygons, drops point and line primitives (noted), keeps authored
// normals, tangents and TEXCOORD_0, generates nothing (see mesh/prepare_mesh.h). UVs come out in the glTF
// convention (origin top-left; Assimp's loaders deliver v up, so v is flipped). Fails with one line naming
// the file for: unreadable file, empty scene, no triangles, out-of-range indices, inf/NaN positions.
// Assimp's own loaders may drop broken faces first (its glTF loader skips a triangle whose index is out of
// range), so a glTF read with another library must still go through validate_mesh. Every file Assimp opens
// and every texture reference is resolved by `policy` (io/files/input_policy.h) relative to the asset's
// folder, and refused outside it; the limits on primitives, vertices, faces and nodes apply (a PLY
// header's counts before Assimp parses, the others right after import). Files Assimp 5.2's OBJ and PLY
// readers cannot read safely are refused before they parse them: a material library with a statement
// before its first newmtl, an OBJ naming itself as its material library, an OBJ of one line, an mtllib
// naming a URL ("://"); a PLY header without end_header, with an element count Assimp would read
// differently (from a name starting with digits) or beyond the bytes that follow, or with a second
// non-empty element of vertices or of faces. The default material Assimp appends (for glTF always) is
// removed: primitives without a material in the file get -1.
Result<ImportedScene> import_mesh(const std::string& path, const MeshImportOptions& options = {},
                                  const io::InputPolicy& policy = {});

}  // namespace specbake
