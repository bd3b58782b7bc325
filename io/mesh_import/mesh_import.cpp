#include "io/mesh_import/mesh_import.h"

#include "io/mesh_import/assimp_policy_io_internal.h"
#include "io/files/file_name.h"
#include "io/files/file_read.h"
#include "io/files/input_policy.h"

#include <assimp/Importer.hpp>
#include <assimp/material.h>
#include <assimp/postprocess.h>
#include <assimp/scene.h>

#include <algorithm>
#include <cctype>
#include <charconv>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <optional>
#include <string_view>

namespace specbake {
using io::over_limit;
namespace {

bool is_gltf(const std::string& path) {
    const std::string ext = io::lower_extension(path);
    return ext == ".gltf" || ext == ".glb";
}

// Where a line ends for Assimp's OBJ, MTL and PLY readers (its IsLineEnd).
bool is_line_end(char c) { return c == '\n' || c == '\r' || c == '\0' || c == '\f'; }

// How Assimp 5.2's PLY header parser (PlyParser.cpp, Element::ParseElement) reads an element line, so that
// the counts bounded below are the ones it allocates by. Words are separated by spaces and tabs; a keyword
// matches when a space or a line end follows it. The element's semantic is one of Assimp's names (vertex,
// face, tristrips, edge, material, TextureFile); for any other name Assimp does not step past the name, and
// reads the count from the name itself: "element 4444444444/245" is an element of 4444444444 mod 2^32
// instances. Counts are read as Assimp's strtoul10 does: the leading digits, modulo 2^32.
struct PlyElementLine {
    std::string name, semantic;  // semantic: empty when Assimp does not know the name
    uint32_t assimp_count = 0;
    std::string count_text;      // the word after the name, as the PLY format has it
};

std::optional<PlyElementLine> parse_ply_element_line(std::string_view line) {
    auto skip_spaces = [&line](size_t i) {
        while (i < line.size() && (line[i] == ' ' || line[i] == '\t')) ++i;
        return i;
    };
    auto word_end = [&line](size_t i) {
        while (i < line.size() && line[i] != ' ' && line[i] != '\t' && !is_line_end(line[i])) ++i;
        return i;
    };
    auto strtoul10 = [&line](size_t i) {
        uint32_t value = 0;
        for (; i < line.size() && line[i] >= '0' && line[i] <= '9'; ++i) value = value * 10u + uint32_t(line[i] - '0');
        return value;
    };
    size_t i = skip_spaces(0);
    if (line.substr(i, word_end(i) - i) != "element") return std::nullopt;
    PlyElementLine out;
    const size_t name_begin = skip_spaces(word_end(i));
    const size_t name_end = word_end(name_begin);
    out.name = std::string(line.substr(name_begin, name_end - name_begin));
    for (const char* known : {"vertex", "face", "tristrips", "edge", "material", "TextureFile"})
        if (out.name == known) out.semantic = known;
    const size_t count_begin = skip_spaces(name_end);
    out.count_text = std::string(line.substr(count_begin, word_end(count_begin) - count_begin));
    out.assimp_count = strtoul10(out.semantic.empty() ? name_begin : count_begin);
    return out;
}

// Assimp 5.2's PLY reader never returns on a file whose header lacks its end_header line (it keeps
// seeking and re-reading the file), so a PLY file (by its "ply" magic, which is what Assimp goes by) is
// refused here unless an end_header line closes its header within the first MiB. Its element counts are
// checked here too, before Assimp sizes its instance lists by them (the counts it reads, see
// parse_ply_element_line): against the vertex and face limits, and against the bytes after the header
// (every instance takes at least one byte). And one element of vertices and one of faces at most: Assimp
// sizes the mesh's vertex and face arrays by the first such element with instances and writes the
// instances of every later one into them (past their end when a later one has more: a heap overflow
// inside the library, which the sanitizers do not see).
Result<void> check_ply_header(const std::string& path, const io::InputLimits& limits) {
    std::ifstream in(path, std::ios::binary);
    // Read in 4 KiB steps until the header's end is in (a header is a few hundred bytes; a whole MiB
    // zeroed for every file was most of the cost of a small import).
    std::string head;
    size_t end = std::string::npos;
    for (char block[4096]; head.size() < (size_t(1) << 20) && in.read(block, sizeof block).gcount() > 0;) {
        head.append(block, size_t(in.gcount()));
        if (head.size() >= 3 && head.compare(0, 3, "ply") != 0) return {};
        end = head.find("\nend_header");
        if (end != std::string::npos && head.size() >= end + 13) break;
    }
    if (head.compare(0, 3, "ply") != 0) return {};
    end = head.find("\nend_header");
    if (end == std::string::npos || (head.compare(end + 11, 1, "\n") != 0 && head.compare(end + 11, 2, "\r\n") != 0))
        return make_error(path + ": PLY header has no end_header line (within its first MiB)");
    std::error_code ec;
    const uint64_t body = std::filesystem::file_size(path, ec) - (end + 12);
    uint64_t instances = 0;
    std::string vertex_element, face_element;  // the first of each with instances
    size_t number = 1;                          // lines counted by '\n'
    for (size_t begin = 0; begin < end;) {
        size_t stop = begin;
        while (stop < end && !is_line_end(head[stop])) ++stop;
        const std::optional<PlyElementLine> element = parse_ply_element_line(std::string_view(head).substr(begin, stop - begin));
        const size_t line_number = number;
        if (head[stop] == '\n') ++number;
        begin = stop + 1;
        if (!element || element->semantic == "TextureFile") continue;
        const std::string where = path + ": PLY element '" + element->name + "' (line " + std::to_string(line_number) + ")";
        uint64_t count = 0;
        const std::string& text = element->count_text;
        const auto [ptr, err] = std::from_chars(text.data(), text.data() + text.size(), count);
        if (text.empty() || err != std::errc() || ptr != text.data() + text.size())
            return make_error(where + " has no valid count ('" + text + "')");
        if (element->semantic.empty() && element->assimp_count != 0)
            return make_error(where + " starts with digits, which Assimp reads as its count (" +
                              std::to_string(element->assimp_count) + ")");
        count = std::max<uint64_t>(count, element->assimp_count);
        const bool vertices = element->semantic == "vertex";
        const bool faces = element->semantic == "face" || element->semantic == "tristrips";
        if (vertices && count > limits.vertices)
            return make_error(where + ": vertex count " + over_limit("vertices", count, limits.vertices));
        if (faces && count > limits.faces)
            return make_error(where + ": face count " + over_limit("faces", count, limits.faces));
        if ((vertices || faces) && element->assimp_count > 0) {
            std::string& first = vertices ? vertex_element : face_element;
            if (!first.empty())
                return make_error(where + " is a second element of " + (vertices ? "vertices" : "faces") +
                                  " (after '" + first + "'); a PLY mesh has one");
            first = element->name;
        }
        instances += count;
        if (!ec && instances > body)
            return make_error(path + ": PLY header claims " + std::to_string(instances) +
                              " element instances but only " + std::to_string(body) + " bytes follow it");
    }
    return {};
}

// Assimp 5.2's OBJ reader copies each line into a buffer of min(file size, 16 MiB) bytes, ends it with
// '\n' but no NUL, and reads a face's indices with atoi (strtol) from that buffer: a line that fills the
// buffer (a file that is one face line) is read past the buffer's end as far as AddressSanitizer's string
// checks go. One line cannot hold a mesh (vertices and faces both): such a file is refused.
Result<void> check_obj_file(const std::filesystem::path& file) {
    std::error_code ec;
    const uint64_t size = std::filesystem::file_size(file, ec);
    if (ec) return {};
    const uint64_t buffer = std::min<uint64_t>(size, uint64_t(1) << 24);
    std::ifstream in(file, std::ios::binary);
    uint64_t run = 0, longest = 0;
    for (char block[65536]; in.read(block, sizeof block), in.gcount() > 0;) {
        for (std::streamsize i = 0; i < in.gcount(); ++i) {
            run = is_line_end(block[i]) ? 0 : run + 1;
            longest = std::max(longest, run);
        }
    }
    if (buffer > 0 && longest + 1 >= buffer)
        return make_error("an OBJ line of " + std::to_string(longest) +
                          " bytes fills the whole file (or 16 MiB); a mesh needs vertex and face lines");
    // Assimp 5.2's file-name cleanup (FileSystemFilter) treats "://" in a name as a URL scheme and erases a
    // negative-length range before it when separators precede it (AddressSanitizer: negative-size-param in
    // std::string::erase). A material library is a file beside the OBJ, never a URL: such an mtllib is refused.
    in.clear();
    in.seekg(0);
    std::string line;
    size_t number = 1;
    char c = 0;
    for (bool more = true; more;) {
        while ((more = bool(in.get(c))) && !is_line_end(c)) line += c;
        const size_t first = line.find_first_not_of(" \t");
        if (first != std::string::npos && line.compare(first, 6, "mtllib") == 0 && line.find("://", first) != std::string::npos)
            return make_error("line " + std::to_string(number) + ": mtllib names a URL ('://'); a material library is a file");
        line.clear();
        if (c == '\n') ++number;
    }
    return {};
}

// Assimp 5.2's MTL reader writes each statement into its current material, which is null until the first
// newmtl: a statement before it (Kd, Ns, map_Kd, ...) crashes the process (a write through a null
// pointer). A material library is read only when every line before its first newmtl is blank or a comment.
Result<void> check_mtl_starts_with_newmtl(const std::filesystem::path& file) {
    std::ifstream in(file, std::ios::binary);
    std::string line;
    size_t number = 1;  // lines counted by '\n'
    char c = 0;
    for (bool more = true; more;) {
        while ((more = bool(in.get(c))) && !is_line_end(c)) line += c;
        const size_t first = line.find_first_not_of(" \t");
        if (first != std::string::npos && line[first] != '#') {
            if (first == 0 && line.compare(0, 6, "newmtl") == 0 &&
                (line.size() == 6 || line[6] == ' ' || line[6] == '\t'))
                return {};
            return make_error("line " + std::to_string(number) + " sets a material property before the first newmtl");
        }
        line.clear();
        if (c == '\n') ++number;
    }
    return {};
}

ImportedMaterial read_material(const aiMaterial& m) {
    ImportedMaterial out;
    aiString name;
    if (m.Get(AI_MATKEY_NAME, name) == AI_SUCCESS) out.name = name.C_Str();
    aiString tex;
    if (m.GetTextureCount(aiTextureType_NORMALS) > 0 && m.GetTexture(aiTextureType_NORMALS, 0, &tex) == AI_SUCCESS) {
        out.has_normal_texture = true;
        out.normal_texture = tex.C_Str();
    }
    // glTF's metallicRoughness texture arrives as DIFFUSE_ROUGHNESS or, in older importers, as UNKNOWN.
    for (aiTextureType type : {aiTextureType_DIFFUSE_ROUGHNESS, aiTextureType_UNKNOWN}) {
        if (m.GetTextureCount(type) > 0 && m.GetTexture(type, 0, &tex) == AI_SUCCESS) {
            out.has_roughness_texture = true;
            out.roughness_texture = tex.C_Str();
            break;
        }
    }
    float value = 0.0f;
    if (m.Get(AI_MATKEY_ROUGHNESS_FACTOR, value) == AI_SUCCESS && std::isfinite(value)) {
        out.roughness_factor = std::clamp(value, 0.0f, 1.0f);
        out.roughness_from_file = true;
    } else if (m.Get(AI_MATKEY_SHININESS, value) == AI_SUCCESS && std::isfinite(value) && value > 0.0f) {
        // Phong exponent to Beckmann: alpha^2 = 2 / (Ns + 2), and r = sqrt(alpha) (SPEC Sec. 2).
        out.roughness_factor = float(std::pow(2.0 / (double(value) + 2.0), 0.25));
    }
    return out;
}

Result<TriMesh> read_mesh(const aiMesh& am, const std::string& path, size_t index) {
    TriMesh m;
    const std::string mesh_name = am.mName.length ? std::string(am.mName.C_Str()) : "#" + std::to_string(index);
    m.name = path + ": mesh '" + mesh_name + "'";
    m.material = int(am.mMaterialIndex);
    const size_t n = am.mNumVertices;
    if (n == 0 || !am.mVertices) return make_error(m.name + ": no vertices");
    m.positions.resize(3 * n);
    for (size_t v = 0; v < n; ++v) {
        const aiVector3D& p = am.mVertices[v];
        if (!std::isfinite(p.x) || !std::isfinite(p.y) || !std::isfinite(p.z))
            return make_error(m.name + ": vertex " + std::to_string(v) + " has a non-finite position");
        m.positions[3 * v] = p.x;
        m.positions[3 * v + 1] = p.y;
        m.positions[3 * v + 2] = p.z;
    }
    if (am.mNormals) {
        m.normals.resize(3 * n);
        for (size_t v = 0; v < n; ++v) {
            m.normals[3 * v] = am.mNormals[v].x;
            m.normals[3 * v + 1] = am.mNormals[v].y;
            m.normals[3 * v + 2] = am.mNormals[v].z;
        }
    }
    if (am.mNormals && am.mTangents && am.mBitangents) {
        // Assimp stores the bitangent; glTF's w is its side of cross(N, T).
        m.tangents.resize(4 * n);
        for (size_t v = 0; v < n; ++v) {
            const aiVector3D& t = am.mTangents[v];
            const aiVector3D b = am.mBitangents[v];
            const aiVector3D nb = am.mNormals[v] ^ t;
            m.tangents[4 * v] = t.x;
            m.tangents[4 * v + 1] = t.y;
            m.tangents[4 * v + 2] = t.z;
            m.tangents[4 * v + 3] = (nb * b) < 0.0f ? -1.0f : 1.0f;
        }
    }
    if (am.mTextureCoords[0]) {
        m.uv0.resize(2 * n);
        for (size_t v = 0; v < n; ++v) {
            m.uv0[2 * v] = am.mTextureCoords[0][v].x;
            m.uv0[2 * v + 1] = 1.0f - am.mTextureCoords[0][v].y;  // Assimp's v up -> glTF's v down
        }
    }
    m.indices.reserve(3 * size_t(am.mNumFaces));
    for (size_t f = 0; f < am.mNumFaces; ++f) {
        const aiFace& face = am.mFaces[f];
        if (face.mNumIndices != 3) continue;  // points and lines left by the loader
        for (int c = 0; c < 3; ++c) {
            if (face.mIndices[c] >= n)
                return make_error(m.name + ": face " + std::to_string(f) + " references vertex " +
                                  std::to_string(face.mIndices[c]) + " but there are only " + std::to_string(n) +
                                  " vertices");
            m.indices.push_back(face.mIndices[c]);
        }
    }
    return m;
}

// Reads `path` with `importer`: read and validated first, post-processed (with `flags`) second. Assimp's
// PLY reader turns a broken face list into faces without indices, which its validation lets through and
// its triangulation stops the process on (an assertion). Such a file is refused in between, and the
// primitive types are recomputed from the faces (the steps run in Assimp's own order either way). Null
// when Assimp could not read the file (its error string says why).
Result<const aiScene*> read_and_post_process(Assimp::Importer& importer, const std::string& path, unsigned flags) {
    const aiScene* scene = nullptr;
    try {
        scene = importer.ReadFile(path, aiProcess_ValidateDataStructure);
        if (scene) {
            for (unsigned i = 0; i < scene->mNumMeshes; ++i) {
                aiMesh& am = *scene->mMeshes[i];
                unsigned types = 0;
                for (unsigned f = 0; f < am.mNumFaces; ++f) {
                    const unsigned n = am.mFaces[f].mNumIndices;
                    if (n == 0)
                        return make_error(path + ": face " + std::to_string(f) + " of mesh " + std::to_string(i) +
                                          " has no vertex indices");
                    types |= n == 1 ? aiPrimitiveType_POINT : n == 2 ? aiPrimitiveType_LINE
                             : n == 3                ? aiPrimitiveType_TRIANGLE
                                                     : aiPrimitiveType_POLYGON;
                }
                am.mPrimitiveTypes = types;
            }
            scene = importer.ApplyPostProcessing(flags & ~unsigned(aiProcess_ValidateDataStructure));
        }
    } catch (const std::exception& e) {
        return make_error(path + ": " + e.what());
    }
    return scene;
}

// Assimp's loaders allocate as they parse; the counts are checked as soon as they are known, before the
// meshes are copied (see check_ply_header for the one format checked before parsing).
Result<void> check_scene_counts(const aiScene& scene, const std::string& path, const io::InputLimits& limits) {
    if (scene.mNumMeshes > limits.primitives)
        return make_error(path + ": mesh count " + over_limit("primitives", scene.mNumMeshes, limits.primitives));
    uint64_t vertices = 0, faces = 0;
    for (size_t i = 0; i < scene.mNumMeshes; ++i) {
        vertices += scene.mMeshes[i]->mNumVertices;
        faces += scene.mMeshes[i]->mNumFaces;
    }
    if (vertices > limits.vertices) return make_error(path + ": vertex count " + over_limit("vertices", vertices, limits.vertices));
    if (faces > limits.faces) return make_error(path + ": face count " + over_limit("faces", faces, limits.faces));
    return {};
}

// The scene's materials. Every texture reference resolves like the files Assimp opened, used by the bake
// or not (embedded textures, "*N", stay as they are); the files of the ones read are kept. Assimp appends
// a default material: always for glTF (unnamed), for other formats when some mesh has none (named
// AI_DEFAULT_MATERIAL_NAME). It is not in the file, so it is left out (primitives using it get material -1).
Result<std::vector<ImportedMaterial>> read_materials(const aiScene& scene, const std::string& path,
                                                     const io::InputPolicy& policy) {
    std::vector<ImportedMaterial> materials;
    const std::filesystem::path folder = std::filesystem::path(path).parent_path();
    for (size_t i = 0; i < scene.mNumMaterials; ++i) {
        const aiMaterial& am = *scene.mMaterials[i];
        ImportedMaterial m = read_material(am);
        for (int type = aiTextureType_NONE; type <= int(AI_TEXTURE_TYPE_MAX); ++type) {
            for (unsigned k = 0; k < am.GetTextureCount(aiTextureType(type)); ++k) {
                aiString tex;
                if (am.GetTexture(aiTextureType(type), k, &tex) != AI_SUCCESS) continue;
                const std::string ref = tex.C_Str();
                if (ref.empty() || ref.starts_with("*")) continue;
                auto resolved = io::resolve_in_folder(folder, ref, policy);
                if (!resolved)
                    return make_error(path + ": texture '" + ref + "' of material '" + m.name + "' refused: " +
                                      resolved.error().message);
                if (m.has_normal_texture && ref == m.normal_texture) m.normal_texture_file = *resolved;
                if (m.has_roughness_texture && ref == m.roughness_texture) m.roughness_texture_file = *resolved;
            }
        }
        materials.push_back(std::move(m));
    }
    if (!materials.empty() && (is_gltf(path) || materials.back().name == AI_DEFAULT_MATERIAL_NAME)) materials.pop_back();
    return materials;
}

// The meshes with triangles into out.meshes (the others noted and skipped); returns each Assimp mesh's
// index in out.meshes, -1 for a skipped one.
Result<std::vector<int>> read_meshes(const aiScene& scene, const std::string& path, ImportedScene& out) {
    std::vector<int> mesh_slot(scene.mNumMeshes, -1);
    for (size_t i = 0; i < scene.mNumMeshes; ++i) {
        const aiMesh& am = *scene.mMeshes[i];
        if (!(am.mPrimitiveTypes & aiPrimitiveType_TRIANGLE)) {
            out.notes.push_back("mesh '" + std::string(am.mName.C_Str()) + "' has no triangles (points or lines), skipped");
            continue;
        }
        Result<TriMesh> m = read_mesh(am, path, i);
        if (!m) return m.error();
        if (m->indices.empty()) {
            out.notes.push_back(m->name + ": no triangles, skipped");
            continue;
        }
        if (m->material >= int(out.materials.size())) m->material = -1;
        mesh_slot[i] = int(out.meshes.size());
        out.meshes.push_back(std::move(m.value()));
    }
    return mesh_slot;
}

// Names of materials, meshes and nodes as UTF-8 text. They are written again as glTF names, which JSON
// requires to be UTF-8, and formats such as OBJ carry whatever bytes the exporter wrote (a Latin-1 'usemtl'
// name). Each byte that starts no UTF-8 sequence becomes U+FFFD, with a note quoting the name as read; the
// geometry and the bake do not depend on names, so the scene is still read rather than refused at the end.
void names_as_utf8(ImportedScene& out) {
    auto fix = [&out](std::string& name, const char* what, const std::string& shown) {
        if (io::is_valid_utf8(name)) return;
        out.notes.push_back(out.path + ": " + what + " name '" + io::escape_invalid_utf8(shown) +
                            "' is not valid UTF-8; each invalid byte is written as U+FFFD (glTF names are UTF-8)");
        name = io::to_valid_utf8(name);
    };
    for (ImportedMaterial& m : out.materials) fix(m.name, "material", m.name);
    // A mesh's name is labelled with the file (read_mesh); the note quotes the file's part.
    const std::string mesh_label = out.path + ": mesh '";
    for (TriMesh& m : out.meshes) {
        const bool labelled = m.name.starts_with(mesh_label) && m.name.ends_with("'");
        fix(m.name, "mesh", labelled ? m.name.substr(mesh_label.size(), m.name.size() - mesh_label.size() - 1) : m.name);
    }
    for (ImportedNode& n : out.nodes) fix(n.name, "node", n.name);
}

// The node hierarchy into out.nodes, depth first in child order, without recursion (a deep hierarchy is a
// file's choice, the stack's depth is not); its size is bounded by the node limit.
Result<void> read_nodes(const aiScene& scene, const std::string& path, const std::vector<int>& mesh_slot,
                        const io::InputLimits& limits, ImportedScene& out) {
    std::vector<std::pair<const aiNode*, int>> stack;
    if (scene.mRootNode) stack.push_back({scene.mRootNode, -1});
    while (!stack.empty()) {
        const auto [node, parent] = stack.back();
        stack.pop_back();
        if (out.nodes.size() >= limits.nodes)
            return make_error(path + ": node count " + over_limit("nodes", out.nodes.size() + 1, limits.nodes));
        ImportedNode n;
        n.name = node->mName.C_Str();
        n.parent = parent;
        const aiMatrix4x4& t = node->mTransformation;  // row-major
        const float rows[4][4] = {{t.a1, t.a2, t.a3, t.a4}, {t.b1, t.b2, t.b3, t.b4},
                                  {t.c1, t.c2, t.c3, t.c4}, {t.d1, t.d2, t.d3, t.d4}};
        for (int c = 0; c < 4; ++c)
            for (int r = 0; r < 4; ++r) n.local_transform[4 * c + r] = rows[r][c];
        for (unsigned k = 0; k < node->mNumMeshes; ++k) {
            const unsigned mi = node->mMeshes[k];
            if (mi < mesh_slot.size() && mesh_slot[mi] >= 0) n.meshes.push_back(mesh_slot[mi]);
        }
        const int self = int(out.nodes.size());
        out.nodes.push_back(std::move(n));
        for (unsigned k = node->mNumChildren; k-- > 0;) stack.push_back({node->mChildren[k], self});
    }
    return {};
}

}  // namespace

Result<ImportedScene> import_mesh(const std::string& path, const MeshImportOptions& options,
                                  const io::InputPolicy& policy) {
    if (auto ok = io::check_regular_input(path); !ok) return ok.error();
    const io::InputLimits& limits = policy.limits;
    if (auto ply = check_ply_header(path, limits); !ply) return ply.error();

    Assimp::Importer importer;
    // Every file Assimp opens (the asset, an OBJ's .mtl, a glTF's buffers) passes the path policy.
    io::AssimpReads reads;
    // The OBJ reader's own checks (check_obj_file, check_mtl_starts_with_newmtl) apply whenever Assimp runs
    // it, whether chosen by the extension or by the content: every file it opens besides the asset, and the
    // asset opened again while it reads it (an mtllib naming the OBJ, or Assimp's guesses from the name
    // landing on it), is a material library. Assimp names the reader it runs in the property "importerIndex".
    const size_t obj_reader = importer.GetImporterIndex("obj");
    auto obj_checks = [&importer, obj_reader](const std::filesystem::path& file, bool asset) -> Result<void> {
        if (obj_reader == size_t(-1) || importer.GetPropertyInteger("importerIndex", -1) != int(obj_reader)) return {};
        return asset ? check_obj_file(file) : check_mtl_starts_with_newmtl(file);
    };
    importer.SetIOHandler(io::new_policy_io_system(path, policy, reads, obj_checks));
    importer.SetPropertyInteger(AI_CONFIG_PP_SBP_REMOVE, aiPrimitiveType_POINT | aiPrimitiveType_LINE);
    unsigned flags = aiProcess_Triangulate | aiProcess_SortByPType | aiProcess_ValidateDataStructure;
    const bool join = options.join == VertexJoin::Always || (options.join == VertexJoin::Auto && !is_gltf(path));
    if (join) flags |= aiProcess_JoinIdenticalVertices;
    auto read = read_and_post_process(importer, path, flags);
    if (!read) return read.error();
    const aiScene* scene = *read;
    // Assimp goes on without a file it could not open (an OBJ without its .mtl gets default materials), so
    // a refusal is an error whether or not the import succeeded.
    if (!reads.refused.empty()) return make_error(path + ": " + reads.refused);
    if (!scene) {
        std::string why = importer.GetErrorString();
        while (!why.empty() && std::isspace(static_cast<unsigned char>(why.back()))) why.pop_back();
        if (why.empty()) why = "unreadable or unsupported mesh file";
        return make_error(path + ": " + why);
    }
    if (scene->mFlags & AI_SCENE_FLAGS_INCOMPLETE) return make_error(path + ": incomplete scene (no meshes)");
    if (auto counts = check_scene_counts(*scene, path, limits); !counts) return counts.error();

    ImportedScene out;
    out.path = path;
    out.files = std::move(reads.files);
    auto materials = read_materials(*scene, path, policy);
    if (!materials) return materials.error();
    out.materials = std::move(*materials);
    auto mesh_slot = read_meshes(*scene, path, out);
    if (!mesh_slot) return mesh_slot.error();
    if (out.meshes.empty()) return make_error(path + ": no triangles in the file");
    if (auto nodes = read_nodes(*scene, path, *mesh_slot, limits, out); !nodes) return nodes.error();
    names_as_utf8(out);
    return out;
}

}  // namespace specbake
