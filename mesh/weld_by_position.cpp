#include "mesh/weld_by_position.h"

#include <tbb/parallel_for.h>

#include <bit>
#include <cmath>

#include "mesh/scratch_array.h"

namespace specbake {
namespace {

constexpr uint32_t kNone = 0xffffffffu;
constexpr int kBucketBits = 8;  // 256 buckets by hash: each welded on its own, in parallel

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
    const bool with_normals = options.split_by_normals && mesh.has_normals();
    const double cos_limit = std::cos(double(options.normal_angle_degrees) * M_PI / 180.0);

    // Pass 1 (parallel): position bits and hash of every vertex.
    // Scratch arrays (uninitialised, huge pages): every element is written before it is read.
    detail::ScratchArray<uint32_t> bits(3 * n);
    detail::ScratchArray<uint64_t> hash(n);
    tbb::parallel_for(tbb::blocked_range<size_t>(0, n, 16384), [&](const auto& r) {
        for (size_t v = r.begin(); v != r.end(); ++v) {
            for (int k = 0; k < 3; ++k) bits[3 * v + k] = coordinate_bits(mesh.positions[3 * v + k]);
            hash[v] = hash_position(&bits[3 * v]);
        }
    });

    // Vertices by bucket (top hash bits), each bucket in vertex order: equal positions share a bucket.
    constexpr size_t kBuckets = size_t(1) << kBucketBits;
    std::vector<uint32_t> bucket_start(kBuckets + 1, 0);
    detail::ScratchArray<uint32_t> order(n);
    for (size_t v = 0; v < n; ++v) ++bucket_start[(hash[v] >> (64 - kBucketBits)) + 1];
    for (size_t b = 0; b < kBuckets; ++b) bucket_start[b + 1] += bucket_start[b];
    {
        std::vector<uint32_t> fill(bucket_start.begin(), bucket_start.end() - 1);
        for (size_t v = 0; v < n; ++v) order[fill[hash[v] >> (64 - kBucketBits)]++] = uint32_t(v);
    }

    // Pass 2 (parallel over buckets): the first vertex of each vertex's position and of its curvature group.
    // Within a position, a vertex joins the first earlier group whose first vertex's normal lies within the
    // angle, else starts a group: the same choice, in the same order, as one sequential pass would make.
    // next_group: per group's first vertex
    detail::ScratchArray<uint32_t> position_first(n), group_first(n), next_group(n);
    tbb::parallel_for(tbb::blocked_range<size_t>(0, kBuckets, 1), [&](const auto& r) {
        std::vector<uint32_t> slot;
        for (size_t b = r.begin(); b != r.end(); ++b) {
            const uint32_t begin = bucket_start[b], end = bucket_start[b + 1];
            size_t capacity = 16;
            while (capacity < 2 * size_t(end - begin)) capacity *= 2;
            slot.assign(capacity, kNone);  // first vertex of each position seen in this bucket
            for (uint32_t i = begin; i < end; ++i) {
                const uint32_t v = order[i];
                const uint32_t* q = &bits[3 * size_t(v)];
                size_t s = hash[v] & (capacity - 1);
                while (slot[s] != kNone) {
                    const uint32_t* o = &bits[3 * size_t(slot[s])];
                    if (o[0] == q[0] && o[1] == q[1] && o[2] == q[2]) break;
                    s = (s + 1) & (capacity - 1);
                }
                if (slot[s] == kNone) slot[s] = v;
                const uint32_t first = slot[s];
                position_first[v] = first;
                // Groups of a position: a chain of first vertices through next_group, starting at `first`.
                uint32_t g = first;
                if (!with_normals || v == first) {
                    group_first[v] = first;
                    if (v == first) next_group[v] = kNone;
                    continue;
                }
                const float* a = &mesh.normals[3 * size_t(v)];
                const double la = double(a[0]) * a[0] + double(a[1]) * a[1] + double(a[2]) * a[2];
                uint32_t last = g;
                group_first[v] = kNone;
                for (; g != kNone; g = next_group[g]) {
                    const float* c = &mesh.normals[3 * size_t(g)];
                    const double dot = double(a[0]) * c[0] + double(a[1]) * c[1] + double(a[2]) * c[2];
                    const double lc = double(c[0]) * c[0] + double(c[1]) * c[1] + double(c[2]) * c[2];
                    if (dot >= cos_limit * std::sqrt(la * lc)) {
                        group_first[v] = g;
                        break;
                    }
                    last = g;
                }
                if (group_first[v] == kNone) {
                    group_first[v] = v;
                    next_group[last] = v;
                    next_group[v] = kNone;
                }
            }
        }
    });

    // Pass 3: ids in order of first occurrence (first vertices precede the vertices that refer to them).
    for (size_t v = 0; v < n; ++v) {
        out.position_id[v] = position_first[v] == v ? out.position_count++ : out.position_id[position_first[v]];
        if (group_first[v] == v) {
            out.group_id[v] = out.group_count++;
            out.group_vertex.push_back(uint32_t(v));
        } else {
            out.group_id[v] = out.group_id[group_first[v]];
        }
    }
    return out;
}

}  // namespace specbake
