// libFuzzer target: OBJ and PLY through Assimp (io/mesh_import/mesh_import.h). An input starting with "ply" is a .ply
// file, any other an .obj; an imported scene must satisfy what import_mesh promises.
#include "fuzz/fuzz_common.h"
#include "io/mesh_import/mesh_import.h"

#include <cmath>
#include <cstring>

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
    const bool ply = size >= 3 && std::memcmp(data, "ply", 3) == 0;
    const auto path = specbake::fuzz::write_scratch(ply ? "mesh.ply" : "mesh.obj", data, size);
    auto scene = specbake::import_mesh(path.string());
    if (!scene) return 0;
    for (const specbake::TriMesh& m : scene->meshes) {
        if (m.indices.size() % 3 != 0 || m.triangle_count() == 0) __builtin_trap();
        for (uint32_t i : m.indices)
            if (i >= m.vertex_count()) __builtin_trap();
        for (float p : m.positions)
            if (!std::isfinite(p)) __builtin_trap();
        if (m.material >= int(scene->materials.size())) __builtin_trap();
    }
    return 0;
}
