// Assimp import (issue 4 item 1): glTF primitives arrive with the file's vertex order, positions, UVs
// (back in glTF's v-down convention), indices and tangent handedness bit for bit, checked against the raw
// accessors read straight from the .gltf/.bin; errors name the file.
#include <gtest/gtest.h>

#include <unistd.h>

#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <set>
#include <nlohmann/json.hpp>

#include "io/mesh_import/mesh_import.h"
#include "mesh/procedural_shapes.h"

namespace specbake {
namespace {

namespace fs = std::filesystem;
using json = nlohmann::json;

// Raw accessor values of a non-sparse accessor, converted to uint32 (indices) or float.
struct Gltf {
    json doc;
    std::vector<std::vector<char>> buffers;

    bool load(const fs::path& file) {
        std::ifstream in(file);
        doc = json::parse(in, nullptr, false);
        if (doc.is_discarded()) return false;
        for (const json& b : doc.value("buffers", json::array())) {
            const std::string uri = b.value("uri", "");
            if (uri.empty() || uri.rfind("data:", 0) == 0) return false;
            std::ifstream bin(file.parent_path() / uri, std::ios::binary);
            buffers.emplace_back(std::istreambuf_iterator<char>(bin), std::istreambuf_iterator<char>());
        }
        return true;
    }
    template <class T>
    std::vector<T> read(int accessor_index, int components) const {
        const json& a = doc["accessors"][accessor_index];
        const json& view = doc["bufferViews"][a["bufferView"].get<int>()];
        const int type = a["componentType"];
        const size_t size = type == 5126 || type == 5125 ? 4 : type == 5123 ? 2 : 1;
        const size_t stride = view.value("byteStride", size_t(0)) ? view.value("byteStride", size_t(0)) : size * components;
        const char* base = buffers[view["buffer"].get<int>()].data() + view.value("byteOffset", size_t(0)) +
                           a.value("byteOffset", size_t(0));
        std::vector<T> out;
        for (size_t i = 0; i < a["count"].get<size_t>(); ++i)
            for (int c = 0; c < components; ++c) {
                const char* p = base + i * stride + c * size;
                if (type == 5126) {
                    float f;
                    std::memcpy(&f, p, 4);
                    out.push_back(T(f));
                } else if (type == 5125) {
                    uint32_t u;
                    std::memcpy(&u, p, 4);
                    out.push_back(T(u));
                } else if (type == 5123) {
                    uint16_t u;
                    std::memcpy(&u, p, 2);
                    out.push_back(T(u));
                } else {
                    out.push_back(T(static_cast<unsigned char>(*p)));
                }
            }
        return out;
    }
};

std::vector<fs::path> shared_gltf_files() {
    std::vector<fs::path> files;
    for (const char* folder : {"gltf", "meshes"}) {
        const fs::path dir = fs::path(SPECBAKE_ASSETS_DIR) / folder;
        if (!fs::is_directory(dir)) continue;
        for (const auto& e : fs::recursive_directory_iterator(dir))
            if (e.path().extension() == ".gltf") files.push_back(e.path());
    }
    std::sort(files.begin(), files.end());
    return files;
}

TEST(MeshImport, GltfPrimitivesKeepTheFilesVertexData) {
    const std::vector<fs::path> files = shared_gltf_files();
    if (files.empty()) GTEST_SKIP() << "shared assets not found at " << SPECBAKE_ASSETS_DIR;
    for (const fs::path& file : files) {
        Gltf g;
        ASSERT_TRUE(g.load(file)) << file;
        Result<ImportedScene> scene = import_mesh(file.string());
        ASSERT_TRUE(scene.ok()) << scene.error().message;
        // Assimp need not keep the file's material order either: a file's material is found among the
        // imported ones by its name where the file's names are unique, else by its index.
        const json materials = g.doc.value("materials", json::array());
        std::set<std::string> names;
        for (const json& mat : materials) names.insert(mat.value("name", std::string()));
        const bool by_name = names.size() == materials.size() && !names.count("");
        auto imported_material = [&](size_t file_index) -> size_t {
            if (!by_name) return file_index;
            const std::string name = materials[file_index].value("name", std::string());
            for (size_t i = 0; i < scene->materials.size(); ++i)
                if (scene->materials[i].name == name) return i;
            return scene->materials.size();
        };
        // Assimp need not keep the file's primitive order (IridescentDishWithOlives comes out reordered):
        // each triangle primitive is matched with the one imported mesh holding exactly its positions.
        size_t k = 0;
        std::vector<bool> matched(scene->meshes.size(), false);
        for (const json& mesh : g.doc["meshes"])
            for (const json& prim : mesh["primitives"]) {
                if (prim.value("mode", 4) != 4) continue;
                const json& attr = prim["attributes"];
                const std::vector<float> positions = g.read<float>(attr["POSITION"], 3);
                size_t found = scene->meshes.size();
                for (size_t i = 0; i < scene->meshes.size() && found == scene->meshes.size(); ++i)
                    if (!matched[i] && scene->meshes[i].positions == positions) found = i;
                ASSERT_LT(found, scene->meshes.size()) << file << ": no imported mesh has primitive " << k
                                                       << "'s positions";
                matched[found] = true;
                ++k;
                const TriMesh& m = scene->meshes[found];
                if (attr.contains("NORMAL")) EXPECT_EQ(m.normals, g.read<float>(attr["NORMAL"], 3)) << file;
                if (attr.contains("TEXCOORD_0") && g.doc["accessors"][attr["TEXCOORD_0"].get<int>()]["componentType"] == 5126) {
                    const std::vector<float> uv = g.read<float>(attr["TEXCOORD_0"], 2);
                    ASSERT_EQ(m.uv0.size(), uv.size()) << file;
                    // v goes through 1 - (1 - v) in float: equal to rounding.
                    for (size_t i = 0; i < uv.size(); ++i) EXPECT_NEAR(m.uv0[i], uv[i], 1e-6) << file << " " << i;
                }
                if (attr.contains("TANGENT")) {
                    const std::vector<float> t = g.read<float>(attr["TANGENT"], 4);
                    ASSERT_EQ(m.tangents.size(), t.size()) << file;
                    for (size_t i = 3; i < t.size(); i += 4) EXPECT_EQ(m.tangents[i], t[i] < 0 ? -1.0f : 1.0f) << file;
                }
                if (prim.contains("indices")) EXPECT_EQ(m.indices, g.read<uint32_t>(prim["indices"], 1)) << file;
                if (prim.contains("material"))
                    EXPECT_EQ(size_t(m.material), imported_material(prim["material"].get<size_t>())) << file;
            }
        EXPECT_EQ(k, scene->meshes.size()) << file;
        // Materials no primitive uses (MaterialsVariantsShoe's variants) need not be imported.
        std::set<size_t> used;
        for (const json& mesh : g.doc["meshes"])
            for (const json& prim : mesh["primitives"])
                if (prim.contains("material")) used.insert(prim["material"].get<size_t>());
        EXPECT_GE(scene->materials.size(), used.size()) << file;
        for (const size_t i : used) {
            const json& mat = materials[i];
            const size_t j = imported_material(i);
            ASSERT_LT(j, scene->materials.size()) << file << " material " << i << " not imported";
            EXPECT_EQ(scene->materials[j].has_normal_texture, mat.contains("normalTexture")) << file << " material " << i;
            const float roughness = mat.value("pbrMetallicRoughness", json::object()).value("roughnessFactor", 1.0f);
            EXPECT_FLOAT_EQ(scene->materials[j].roughness_factor, roughness) << file << " material " << i;
        }
    }
}

TEST(MeshImport, ObjSoupIsJoinedAndUvsAreGltfOriented) {
    const fs::path path = fs::temp_directory_path() / "specbake_import_quad.obj";
    {
        std::ofstream f(path);
        f << "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nvt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\nvn 0 0 1\n"
             "f 1/1/1 2/2/1 3/3/1 4/4/1\n";
    }
    Result<ImportedScene> scene = import_mesh(path.string());
    fs::remove(path);
    ASSERT_TRUE(scene.ok()) << scene.error().message;
    ASSERT_EQ(scene->meshes.size(), 1u);
    const TriMesh& m = scene->meshes[0];
    EXPECT_EQ(m.triangle_count(), 2u);
    EXPECT_EQ(m.vertex_count(), 4u);  // joined: the quad's two triangles share two corners
    for (size_t v = 0; v < m.vertex_count(); ++v) {
        // OBJ's vt has v up (y = 1 at the top); glTF's v is 0 at the top.
        EXPECT_FLOAT_EQ(m.uv0[2 * v + 1], 1.0f - m.positions[3 * v + 1]);
    }
}

TEST(MeshImport, ErrorsNameTheFile) {
    Result<ImportedScene> missing = import_mesh("/nonexistent/folder/model.fbx");
    ASSERT_FALSE(missing.ok());
    EXPECT_NE(missing.error().message.find("model.fbx"), std::string::npos);
    const fs::path garbage = fs::temp_directory_path() / "specbake_import_garbage.ply";
    {
        std::ofstream f(garbage);
        f << "ply\nformat ascii 1.0\nelement vertex 2\nproperty float x\nend_header\n1\n";
    }
    Result<ImportedScene> bad = import_mesh(garbage.string());
    fs::remove(garbage);
    ASSERT_FALSE(bad.ok());
    EXPECT_NE(bad.error().message.find("specbake_import_garbage.ply"), std::string::npos);
    EXPECT_EQ(bad.error().message.find('\n'), std::string::npos);
}

// Found by fuzz/fuzz_mesh.cpp: Assimp's PLY reader never returns on a header that lacks its end_header
// line (missing, or misspelt "end_headers"); import_mesh refuses such a file before Assimp reads it. On the
// old code this test does not finish (ctest's timeout fails it).
TEST(MeshImport, PlyWithoutEndHeaderLineIsRefused) {
    const std::string header =
        "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\n"
        "element face 1\nproperty list uchar int vertex_indices\n";
    const std::string body = "0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n";
    for (const std::string& closing : {std::string(), std::string("end_headers\n"), std::string("end_header_\n")}) {
        const fs::path path = fs::temp_directory_path() / ("specbake_import_no_end_" + std::to_string(::getpid()) + ".ply");
        std::ofstream(path, std::ios::binary) << header << closing << body;
        Result<ImportedScene> bad = import_mesh(path.string());
        fs::remove(path);
        ASSERT_FALSE(bad.ok()) << "closing line '" << closing << "'";
        EXPECT_NE(bad.error().message.find(path.filename().string() + ": PLY header has no end_header line"),
                  std::string::npos)
            << bad.error().message;
    }
    // The same file with its end_header line (also with CRLF line ends) still imports.
    for (const std::string& closing : {std::string("end_header\n"), std::string("end_header\r\n")}) {
        const fs::path path = fs::temp_directory_path() / ("specbake_import_end_" + std::to_string(::getpid()) + ".ply");
        std::ofstream(path, std::ios::binary) << header << closing << body;
        Result<ImportedScene> good = import_mesh(path.string());
        fs::remove(path);
        ASSERT_TRUE(good.ok()) << good.error().message;
        EXPECT_EQ(good->meshes.at(0).triangle_count(), 1u);
    }
}

// Found by fuzz/fuzz_mesh.cpp (fuzz/regressions/mesh/ply-second-face-element-heap-overflow.ply): Assimp 5.2's
// PLY reader sizes the mesh's face array by the first face element and writes the faces of every later one
// into it, past its end when a later one has more (a heap overflow inside the uninstrumented library, seen
// by the sanitizers only later, as a corrupted allocator or a leak report); the same holds for vertices. A
// header with a second non-empty element of vertices or faces (face and tristrips both are) is refused.
// On the old code the files below import (or overflow the heap).
TEST(MeshImport, PlyWithASecondVertexOrFaceElementIsRefused) {
    const fs::path path = fs::temp_directory_path() / ("specbake_import_second_" + std::to_string(::getpid()) + ".ply");
    const std::string vertices = "element vertex 3\nproperty float x\nproperty float y\nproperty float z\n";
    const std::string faces = "element face 1\nproperty list uchar int vertex_indices\n";
    const std::string body = "0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n";
    struct Case {
        std::string header, body, second;  // second: "NAME' (line N)", the second element
    };
    for (const Case& c : {
             Case{vertices + faces + faces, body + "3 0 1 2\n", "face' (line 9)"},
             Case{vertices + faces + "element face 2\nproperty list uchar int vertex_indices\n",
                  body + "3 0 1 2\n3 0 1 2\n", "face' (line 9)"},
             Case{vertices + faces + "element tristrips 1\nproperty list int int vertex_indices\n",
                  body + "3 0 1 2\n", "tristrips' (line 9)"},
             Case{vertices + vertices + faces, "0 0 0\n1 0 0\n0 1 0\n" + body, "vertex' (line 7)"},
         }) {
        std::ofstream(path, std::ios::binary) << "ply\nformat ascii 1.0\n" << c.header << "end_header\n" << c.body;
        Result<ImportedScene> bad = import_mesh(path.string());
        ASSERT_FALSE(bad.ok()) << c.header;
        EXPECT_NE(bad.error().message.find(path.filename().string() + ": PLY element '" + c.second),
                  std::string::npos)
            << bad.error().message;
        EXPECT_NE(bad.error().message.find("is a second element of"), std::string::npos) << bad.error().message;
    }
    // An empty second element, a comment naming one and the plain file import, with the file's one face.
    for (const std::string& extra : {std::string("element face 0\nproperty list uchar int vertex_indices\n"),
                                     std::string("comment face 7 vertex 9\n"), std::string()}) {
        std::ofstream(path, std::ios::binary) << "ply\nformat ascii 1.0\n" << vertices << faces << extra
                                              << "end_header\n" << body;
        Result<ImportedScene> good = import_mesh(path.string());
        ASSERT_TRUE(good.ok()) << extra << good.error().message;
        EXPECT_EQ(good->meshes.at(0).triangle_count(), 1u) << extra;
    }
    fs::remove(path);
}

// Found by fuzz/fuzz_mesh.cpp (fuzz/regressions/mesh/ply-element-count-read-from-name.ply): Assimp 5.2 reads
// the count of an element whose name it does not know from the name itself ("element 4444444444/245" has
// 4444444444 mod 2^32 instances), and sized a list of 2.6 billion instances by one (62 GB; the sanitizer's
// allocator gives up). A count is the word after the name; a name Assimp would read as one is refused, and
// the count Assimp reads is bounded like the written one. On the old code this test fails (or runs out of
// memory).
TEST(MeshImport, PlyElementCountsAreTheOnesAssimpReads) {
    const fs::path path = fs::temp_directory_path() / ("specbake_import_count_" + std::to_string(::getpid()) + ".ply");
    struct Case {
        std::string line, error;
    };
    for (const Case& c : {
             Case{"element 44444444444444444444444444444/245", "has no valid count ('')"},
             Case{"element 44444444444444444444444444444/245 1", "starts with digits, which Assimp reads as its count (2624702236)"},
             Case{"element 7 0", "starts with digits, which Assimp reads as its count (7)"},
             Case{"element vertex", "has no valid count ('')"},
             Case{"element\tface\t 12x", "has no valid count ('12x')"},
         }) {
        std::ofstream(path, std::ios::binary) << "ply\nformat ascii 1.0\n" << c.line << "\nproperty float x\nend_header\n0\n";
        Result<ImportedScene> bad = import_mesh(path.string());
        ASSERT_FALSE(bad.ok()) << c.line;
        EXPECT_NE(bad.error().message.find(path.filename().string() + ": PLY element '"), std::string::npos)
            << bad.error().message;
        EXPECT_NE(bad.error().message.find(c.error), std::string::npos) << c.line << ": " << bad.error().message;
    }
    // 2624702236 is 44444444444444444444444444444 = 4 (10^29 - 1) / 9 modulo 2^32, in 128-bit arithmetic:
    unsigned __int128 ten29 = 1;
    for (int k = 0; k < 29; ++k) ten29 *= 10;
    EXPECT_EQ(uint64_t(4 * (ten29 - 1) / 9 % (uint64_t(1) << 32)), 2624702236u);
    fs::remove(path);
}

// Every reproducer of fuzz/regressions/mesh/ (the fuzz target's inputs: "ply..." a .ply, any other an .obj)
// goes through import_mesh in a folder of its own and is refused with a line naming the file; under the
// sanitizer build this replays the crashes themselves.
TEST(MeshImport, FuzzRegressionsAreRefused) {
    const fs::path regressions = fs::path(SPECBAKE_SOURCE_DIR) / "fuzz/regressions/mesh";
    const fs::path dir = fs::temp_directory_path() / ("specbake_import_regressions_" + std::to_string(::getpid()));
    size_t replayed = 0;
    for (const fs::directory_entry& entry : fs::directory_iterator(regressions)) {
        std::ifstream in(entry.path(), std::ios::binary);
        const std::string data((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
        fs::remove_all(dir);
        fs::create_directories(dir);
        const fs::path file = dir / (data.compare(0, 3, "ply") == 0 ? "mesh.ply" : "mesh.obj");
        std::ofstream(file, std::ios::binary) << data;
        Result<ImportedScene> scene = import_mesh(file.string());
        EXPECT_FALSE(scene.ok()) << entry.path().filename();
        if (!scene.ok()) {
            EXPECT_EQ(scene.error().message.rfind(file.string() + ": ", 0), 0u) << scene.error().message;
            EXPECT_EQ(scene.error().message.find('\n'), std::string::npos) << scene.error().message;
        }
        ++replayed;
    }
    fs::remove_all(dir);
    EXPECT_GE(replayed, 16u);
}

// Found by fuzz/fuzz_mesh.cpp (fuzz/regressions/mesh/obj-mtllib-*): Assimp 5.2's MTL reader writes a
// statement before the first newmtl through a null material, and the process dies (SEGV). import_mesh
// refuses such a material library, named by the OBJ, by its extension or its content, or the OBJ itself.
// On the old code this test crashes.
TEST(MeshImport, MaterialLibraryWithAStatementBeforeNewmtlIsRefused) {
    const fs::path dir = fs::temp_directory_path() / ("specbake_import_mtl_" + std::to_string(::getpid()));
    fs::create_directories(dir);
    const std::string triangle = "usemtl m\nv 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n";
    std::ofstream(dir / "early.mtl", std::ios::binary) << "# exported\n\nKd 1 0 0\nnewmtl m\nNs 30\n";
    std::ofstream(dir / "good.mtl", std::ios::binary) << "# exported\n  \t\n\r\nnewmtl m\nNs 30\n";
    for (const std::string name : {"early.obj", "early.unknownext"}) {
        std::ofstream(dir / name, std::ios::binary) << "mtllib early.mtl\n" << triangle;
        Result<ImportedScene> bad = import_mesh((dir / name).string());
        ASSERT_FALSE(bad.ok()) << name;
        EXPECT_NE(bad.error().message.find(name + ": referenced file 'early.mtl' refused: line 3 sets a material "
                                                  "property before the first newmtl"),
                  std::string::npos)
            << bad.error().message;
    }
    // An OBJ that names itself as its material library (directly, as the fallback library name of a file
    // named *.mtl, or through the names Assimp's FileSystemFilter derives from a missing one: it tries
    // FOLDER/ + as many characters after each '/' as the last part has, plus one) is read as one while it
    // is being read.
    for (const auto& [name, text] :
         {std::pair<std::string, std::string>{"self.obj", "mtllib self.obj\n"},
          {"self.mtl", "mtllib missing.mtl\n"},
          {"mangled.obj", "mtllib mangled.objABCDE/1234567890\nmap_Kd x.png\n"}}) {
        std::ofstream(dir / name, std::ios::binary) << text << triangle;
        Result<ImportedScene> self = import_mesh((dir / name).string());
        ASSERT_FALSE(self.ok()) << text;
        EXPECT_NE(self.error().message.find(name + ": referenced file '" + name +
                                            "' refused: line 1 sets a material property before the first newmtl"),
                  std::string::npos)
            << self.error().message;
    }
    // Blank and comment lines before newmtl are fine, whatever the extension of the OBJ.
    for (const std::string name : {"good.obj", "good.unknownext"}) {
        std::ofstream(dir / name, std::ios::binary) << "mtllib good.mtl\n" << triangle;
        Result<ImportedScene> good = import_mesh((dir / name).string());
        ASSERT_TRUE(good.ok()) << good.error().message;
        EXPECT_EQ(good->meshes.at(0).triangle_count(), 1u);
        const int material = good->meshes[0].material;
        ASSERT_GE(material, 0) << name;
        EXPECT_EQ(good->materials.at(size_t(material)).name, "m") << name;
        EXPECT_FLOAT_EQ(good->materials[size_t(material)].roughness_factor, float(std::pow(2.0 / 32.0, 0.25)))
            << name;  // Ns 30, read from good.mtl
    }
    fs::remove_all(dir);
}

// Found by fuzz/fuzz_mesh.cpp (fuzz/regressions/mesh/obj-one-line-face-strtol-*): Assimp 5.2's OBJ reader
// reads the indices of a line that fills its line buffer with atoi past the buffer's end (no NUL after
// it), which the sanitizers' string checks report. One line cannot hold a mesh: such a file is refused.
TEST(MeshImport, ObjFileOfOneLineIsRefused) {
    const fs::path path = fs::temp_directory_path() / ("specbake_import_one_line_" + std::to_string(::getpid()) + ".obj");
    for (const std::string text : {"f 1 2 3\n", "l 1 2", "p 1\n"}) {
        std::ofstream(path, std::ios::binary) << text;
        Result<ImportedScene> bad = import_mesh(path.string());
        ASSERT_FALSE(bad.ok()) << text;
        EXPECT_NE(bad.error().message.find(path.filename().string() + ": an OBJ line of "), std::string::npos)
            << bad.error().message;
        EXPECT_NE(bad.error().message.find("fills the whole file"), std::string::npos) << bad.error().message;
    }
    fs::remove(path);
}

// An mtllib naming a URL ("://") is refused before Assimp's file-name cleanup sees it (it erased a negative
// length on such names); an ordinary mtllib beside it still imports.
TEST(MeshImport, ObjMaterialLibraryNamedAsAUrlIsRefused) {
    const fs::path dir = fs::temp_directory_path() / ("specbake_import_url_" + std::to_string(::getpid()));
    fs::create_directories(dir);
    const std::string mesh = "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n";
    std::ofstream(dir / "url.obj", std::ios::binary) << "mtllib no//////://////x.mtl\n" << mesh;
    Result<ImportedScene> bad = import_mesh((dir / "url.obj").string());
    ASSERT_FALSE(bad.ok());
    EXPECT_NE(bad.error().message.find("url.obj: line 1: mtllib names a URL"), std::string::npos) << bad.error().message;
    std::ofstream(dir / "m.mtl", std::ios::binary) << "newmtl a\nKd 1 1 1\n";
    std::ofstream(dir / "file.obj", std::ios::binary) << "mtllib m.mtl\n" << mesh;
    EXPECT_TRUE(import_mesh((dir / "file.obj").string()).ok());
    fs::remove_all(dir);
}

}  // namespace
}  // namespace specbake
