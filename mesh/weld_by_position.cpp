#include "mesh/weld_by_position.h"

#include <bit>
#include <cmath>
#include <cstring>

namespace specbake {
namespace {

constexpr uint32_t kNone = 0xffffffffu;

// Bit pattern of a coordinate with -0 mapped to +0, so the two compare equal as they do numerically.
uint32_t coordinate_bits(float x) {
    if (x == 0.0f) x = 0.0f;
    return std::bit_cast<uint32_t>(x);
}

uint64_t hash_position(const uint32_t b[3]) {
    uint64_t h = b[0] * 0x9E3779B97F4A7C15ull;
    h ^= (h >> 29) + b[1] * 0xBF58476D1CE4E5B9ull;
    h ^= (h >> 31) + b[2] * 0x94D049BB133111EBull;
    return h ^ (h >> 32);
}

}  // namespace

WeldedTopology weld_by_position(const TriMesh& mesh, const WeldOptions& options) {
    const size_t n = mesh.vertex_count();
    WeldedTopology out;
    out.position_id.assign(n, 0);
    out.group_id.assign(n, 0);

    // Open addressing over first-occurrence vertices; capacity a power of two at least twice n.
    size_t capacity = 16;
    while (capacity < 2 * n) capacity *= 2;
    std::vector<uint32_t> slot(capacity, kNone);
    std::vector<uint32_t> position_bits;  // 3 per topological vertex
    position_bits.reserve(3 * n);

    // Curvature groups of one position form a singly linked list: first group per position, next group.
    std::vector<uint32_t> first_group;
    std::vector<uint32_t> next_group;
    std::vector<uint32_t>& group_vertex = out.group_vertex;
    const bool with_normals = options.split_by_normals && mesh.has_normals();
    const double cos_limit = std::cos(double(options.normal_angle_degrees) * M_PI / 180.0);

    for (size_t v = 0; v < n; ++v) {
        const uint32_t b[3] = {coordinate_bits(mesh.positions[3 * v]), coordinate_bits(mesh.positions[3 * v + 1]),
                               coordinate_bits(mesh.positions[3 * v + 2])};
        size_t s = hash_position(b) & (capacity - 1);
        uint32_t pid = kNone;
        while (slot[s] != kNone) {
            const uint32_t* q = &position_bits[3 * slot[s]];
            if (q[0] == b[0] && q[1] == b[1] && q[2] == b[2]) {
                pid = slot[s];
                break;
            }
            s = (s + 1) & (capacity - 1);
        }
        if (pid == kNone) {
            pid = out.position_count++;
            slot[s] = pid;
            position_bits.insert(position_bits.end(), b, b + 3);
            first_group.push_back(kNone);
        }
        out.position_id[v] = pid;

        uint32_t gid = kNone;
        uint32_t* link = &first_group[pid];
        while (*link != kNone) {
            const uint32_t g = *link;
            if (!with_normals) {
                gid = g;
                break;
            }
            const float* a = &mesh.normals[3 * size_t(v)];
            const float* c = &mesh.normals[3 * size_t(group_vertex[g])];
            const double dot = double(a[0]) * c[0] + double(a[1]) * c[1] + double(a[2]) * c[2];
            const double la = double(a[0]) * a[0] + double(a[1]) * a[1] + double(a[2]) * a[2];
            const double lc = double(c[0]) * c[0] + double(c[1]) * c[1] + double(c[2]) * c[2];
            if (dot >= cos_limit * std::sqrt(la * lc)) {
                gid = g;
                break;
            }
            link = &next_group[g];
        }
        if (gid == kNone) {
            gid = out.group_count++;
            *link = gid;
            next_group.push_back(kNone);
            group_vertex.push_back(uint32_t(v));
        }
        out.group_id[v] = gid;
    }
    return out;
}

}  // namespace specbake
