#include <tbb/parallel_for.h>
#include <tbb/parallel_invoke.h>
#include <tbb/parallel_reduce.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <numeric>
#include <unordered_map>

#if defined(__x86_64__)
#include <immintrin.h>
#endif

#include "core/assert.h"
#include "mesh/halfedge_mesh.h"
#include "mesh/mesh_math.h"
#include "mesh/scratch_array.h"

namespace specbake {
namespace {

constexpr uint32_t kNone = 0xffffffffu;

// Corners are 3 * face + c; the halfedge of corner k runs from k to next_corner(k) inside its face.
inline uint32_t next_corner(uint32_t k) { return k % 3 == 2 ? k - 2 : k + 1; }
inline uint32_t prev_corner(uint32_t k) { return k % 3 == 0 ? k + 2 : k - 1; }

// True when the link of a position (the edges opposite it in its triangles, `corners` its corners) is one
// path or one cycle, i.e. its triangles form a single fan.
bool link_is_single_fan(const detail::ScratchArray<uint32_t>& pos, const uint32_t* corners, uint32_t count) {
    std::vector<uint32_t> ends, ids, parent, degree;
    for (uint32_t i = 0; i < count; ++i) {
        ends.push_back(pos[next_corner(corners[i])]);
        ends.push_back(pos[prev_corner(corners[i])]);
    }
    ids = ends;
    std::sort(ids.begin(), ids.end());
    ids.erase(std::unique(ids.begin(), ids.end()), ids.end());
    parent.resize(ids.size());
    std::iota(parent.begin(), parent.end(), 0u);
    degree.assign(ids.size(), 0);
    auto find = [&](uint32_t x) {
        while (parent[x] != x) x = parent[x] = parent[parent[x]];
        return x;
    };
    size_t components = ids.size();
    for (size_t k = 0; k < ends.size(); k += 2) {
        const uint32_t a = uint32_t(std::lower_bound(ids.begin(), ids.end(), ends[k]) - ids.begin());
        const uint32_t c = uint32_t(std::lower_bound(ids.begin(), ids.end(), ends[k + 1]) - ids.begin());
        if (++degree[a] > 2 || ++degree[c] > 2) return false;
        const uint32_t ra = find(a), rc = find(c);
        if (ra != rc) {
            parent[ra] = rc;
            --components;
        }
    }
    return components == 1;
}

// Edge pairing, per position a: every outgoing halfedge a -> b (corner k at a whose next corner is at b)
// is compared with all of a's corners. A corner j there also runs a -> b when its next corner is at b; the
// halfedge of its previous corner runs b -> a when that corner is at b (the triangle's corners are distinct,
// so never both). An edge is simple when it has one halfedge, or two running opposite ways; those pair up
// (mate). Boundary edges (one halfedge) and non-manifold edges (three or more, counted at their lowest
// halfedge) are summed per range: integer sums, the same for any split.
struct PairingArrays {
    const uint32_t* start;        // per position: first entry in the columns below
    const uint32_t* by_position;  // corners grouped by position, in corner order
    const uint32_t* next;         // per entry: the position of the corner's next corner
    const uint32_t* prev;         // per entry: the position of the corner's previous corner
    uint32_t* mate;               // out, per corner: the paired halfedge or kNone
    uint8_t* simple;              // out, per corner: its edge is simple
};

struct EdgeCounts {
    size_t boundary = 0, nonmanifold = 0, not_simple = 0;
};

// A position's corners: `count` entries of the columns from its start on.
struct Around {
    const uint32_t *next, *prev, *corner;
    uint32_t count;
    Around(const PairingArrays& in, uint32_t a)
        : next(in.next + in.start[a]), prev(in.prev + in.start[a]), corner(in.by_position + in.start[a]),
          count(in.start[a + 1] - in.start[a]) {}
};

// The verdict on outgoing halfedge i of a position, from its counts of same-way and opposite halfedges
// (partner: the last opposite one).
inline void settle(const PairingArrays& in, const Around& c, uint32_t i, uint32_t total, uint32_t opposite,
                   uint32_t partner, EdgeCounts& counts) {
    const uint32_t k = c.corner[i], b = c.next[i];
    const bool paired = total == 2 && opposite == 1;
    const bool simple = total == 1 || paired;
    in.simple[k] = simple;
    in.mate[k] = paired ? partner : kNone;
    counts.boundary += total == 1;
    counts.not_simple += !simple;
    if (total >= 3) {
        uint32_t lowest = k;
        for (uint32_t m = 0; m < c.count; ++m) {
            if (c.next[m] == b) lowest = std::min(lowest, c.corner[m]);
            else if (c.prev[m] == b) lowest = std::min(lowest, prev_corner(c.corner[m]));
        }
        counts.nonmanifold += lowest == k;
    }
}

EdgeCounts pair_positions_scalar(const PairingArrays& in, uint32_t begin, uint32_t end, EdgeCounts counts) {
    for (uint32_t a = begin; a != end; ++a) {
        const Around c(in, a);
        for (uint32_t i = 0; i < c.count; ++i) {
            const uint32_t b = c.next[i];
            uint32_t total = 0, opposite = 0, partner = kNone;
            for (uint32_t m = 0; m < c.count; ++m) {
                const uint32_t same = c.next[m] == b, opp = c.prev[m] == b;
                total += same + opp;
                opposite += opp;
                partner = opp ? prev_corner(c.corner[m]) : partner;
            }
            settle(in, c, i, total, opposite, partner, counts);
        }
    }
    return counts;
}

#if defined(__x86_64__) && defined(__GNUC__)
// The same with eight comparisons per instruction: a position of valence 6 compares each halfedge with all
// of its corners in two AVX2 compares, straight from the columns (they are padded by 8 entries at the end;
// lanes past the position's corners are masked off). Integer logic: the result equals the scalar one.
__attribute__((target("avx2,popcnt,lzcnt"))) EdgeCounts pair_positions_avx2(const PairingArrays& arrays, uint32_t begin,
                                                                           uint32_t end, EdgeCounts counts) {
    const PairingArrays in = arrays;  // a local copy: the byte stores to simple cannot alias its pointers
    for (uint32_t a = begin; a != end; ++a) {
        const Around c(in, a);
        if (c.count <= 8) {
            // Most positions: all corners in one register pair, loaded once (the byte writes of settle
            // would otherwise force reloads), and the next positions kept in a local copy.
            const unsigned lanes = (1u << c.count) - 1u;
            const __m256i nx = _mm256_loadu_si256(reinterpret_cast<const __m256i*>(c.next));
            const __m256i pv = _mm256_loadu_si256(reinterpret_cast<const __m256i*>(c.prev));
            alignas(32) uint32_t next[8];
            _mm256_store_si256(reinterpret_cast<__m256i*>(next), nx);
            for (uint32_t i = 0; i < c.count; ++i) {
                const __m256i b = _mm256_set1_epi32(int(next[i]));
                const unsigned same =
                    lanes & unsigned(_mm256_movemask_ps(_mm256_castsi256_ps(_mm256_cmpeq_epi32(nx, b))));
                const unsigned opp =
                    lanes & unsigned(_mm256_movemask_ps(_mm256_castsi256_ps(_mm256_cmpeq_epi32(pv, b))));
                if ((same & ~(1u << i)) == 0 && (opp & (opp - 1)) == 0) {
                    // The usual verdict: no other halfedge the same way, at most one the opposite way.
                    const uint32_t k = c.corner[i];
                    in.simple[k] = 1;
                    in.mate[k] = opp ? prev_corner(c.corner[unsigned(__builtin_ctz(opp))]) : kNone;
                    counts.boundary += opp == 0;
                    continue;
                }
                const uint32_t opposite = uint32_t(__builtin_popcount(opp));
                const uint32_t total = uint32_t(__builtin_popcount(same)) + opposite;
                const uint32_t partner = opp ? prev_corner(c.corner[31 - unsigned(__builtin_clz(opp))]) : kNone;
                settle(in, c, i, total, opposite, partner, counts);
            }
            continue;
        }
        for (uint32_t i = 0; i < c.count; ++i) {
            const __m256i b = _mm256_set1_epi32(int(c.next[i]));
            uint32_t total = 0, opposite = 0, partner = kNone;
            for (uint32_t m = 0; m < c.count; m += 8) {
                const unsigned lanes = c.count - m >= 8 ? 0xffu : (1u << (c.count - m)) - 1u;
                const __m256i nx = _mm256_loadu_si256(reinterpret_cast<const __m256i*>(c.next + m));
                const __m256i pv = _mm256_loadu_si256(reinterpret_cast<const __m256i*>(c.prev + m));
                const unsigned same =
                    lanes & unsigned(_mm256_movemask_ps(_mm256_castsi256_ps(_mm256_cmpeq_epi32(nx, b))));
                const unsigned opp =
                    lanes & unsigned(_mm256_movemask_ps(_mm256_castsi256_ps(_mm256_cmpeq_epi32(pv, b))));
                total += unsigned(__builtin_popcount(same) + __builtin_popcount(opp));
                opposite += unsigned(__builtin_popcount(opp));
                if (opp) partner = prev_corner(c.corner[m + 31 - unsigned(__builtin_clz(opp))]);
            }
            settle(in, c, i, total, opposite, partner, counts);
        }
    }
    return counts;
}
#endif

EdgeCounts pair_positions(const PairingArrays& in, uint32_t begin, uint32_t end, EdgeCounts counts) {
#if defined(__x86_64__) && defined(__GNUC__)
    static const bool avx2 = __builtin_cpu_supports("avx2") && __builtin_cpu_supports("popcnt");
    if (avx2) return pair_positions_avx2(in, begin, end, counts);
#endif
    return pair_positions_scalar(in, begin, end, counts);
}

// is_degenerate_triangle of three mesh vertices, decided in float where the triangle is clearly not
// degenerate: a component of the float normal above 1e-5 of the float scale means twice the area exceeds
// 1e-10 of the scale by far more than float rounding (some 1e-7 of the scale) could account for. Tiny,
// huge and non-finite input fails that filter and goes to the exact double test.
inline bool degenerate(const TriMesh& mesh, const float* positions, const uint32_t* f) {
    const float *p = positions + 3 * size_t(f[0]), *q = positions + 3 * size_t(f[1]), *r = positions + 3 * size_t(f[2]);
    const float ax = q[0] - p[0], ay = q[1] - p[1], az = q[2] - p[2];
    const float bx = r[0] - p[0], by = r[1] - p[1], bz = r[2] - p[2];
    const float cx = r[0] - q[0], cy = r[1] - q[1], cz = r[2] - q[2];
    const float nx = std::abs(ay * bz - az * by), ny = std::abs(az * bx - ax * bz), nz = std::abs(ax * by - ay * bx);
    const float scale = ax * ax + ay * ay + az * az + bx * bx + by * by + bz * bz + cx * cx + cy * cy + cz * cz;
    if (scale > 1e-30f && std::max(nx, std::max(ny, nz)) > 1e-5f * scale) return false;
    return detail::is_degenerate_triangle(detail::position(mesh, f[0]), detail::position(mesh, f[1]),
                                          detail::position(mesh, f[2]));
}

// Marks triangles [first, last) usable (three distinct positions, not degenerate) and returns how many are.
uint32_t mark_usable_scalar(const TriMesh& mesh, const uint32_t* pid, uint8_t* usable, size_t first, size_t last) {
    const uint32_t* const indices = mesh.indices.data();
    const float* const positions = mesh.positions.data();
    uint32_t count = 0;
    for (size_t t = first; t != last; ++t) {
        const uint32_t* f = indices + 3 * t;
        const uint32_t a = pid[f[0]], b = pid[f[1]], c = pid[f[2]];
        const bool ok = a != b && b != c && a != c && !degenerate(mesh, positions, f);
        usable[t] = ok;
        count += ok;
    }
    return count;
}

#if defined(__x86_64__) && defined(__GNUC__)
// The same for eight triangles at a time: the float filter of degenerate() in AVX2 lanes (the same IEEE
// operations), the exact test only for lanes it does not clear. Needs 3 * vertex_count below 2^31.
__attribute__((target("avx2"))) uint32_t mark_usable_avx2(const TriMesh& mesh, const uint32_t* pid,
                                                               uint8_t* usable, size_t first, size_t last) {
    const int* const indices = reinterpret_cast<const int*>(mesh.indices.data());
    const float* const positions = mesh.positions.data();
    const __m256i stride = _mm256_setr_epi32(0, 3, 6, 9, 12, 15, 18, 21);
    const __m256 sign = _mm256_set1_ps(-0.0f), tiny = _mm256_set1_ps(1e-30f), ratio = _mm256_set1_ps(1e-5f);
    uint32_t count = 0;
    size_t t = first;
    for (; t + 8 <= last; t += 8) {
        const int* f = indices + 3 * t;
        const __m256i f0 = _mm256_i32gather_epi32(f, stride, 4), f1 = _mm256_i32gather_epi32(f + 1, stride, 4),
                      f2 = _mm256_i32gather_epi32(f + 2, stride, 4);
        const int* pid_i = reinterpret_cast<const int*>(pid);
        const __m256i a = _mm256_i32gather_epi32(pid_i, f0, 4), b = _mm256_i32gather_epi32(pid_i, f1, 4),
                      c = _mm256_i32gather_epi32(pid_i, f2, 4);
        const __m256i equal = _mm256_or_si256(_mm256_or_si256(_mm256_cmpeq_epi32(a, b), _mm256_cmpeq_epi32(b, c)),
                                              _mm256_cmpeq_epi32(a, c));
        const unsigned distinct = ~unsigned(_mm256_movemask_ps(_mm256_castsi256_ps(equal))) & 0xffu;
        const __m256i o0 = _mm256_add_epi32(f0, _mm256_add_epi32(f0, f0)),
                      o1 = _mm256_add_epi32(f1, _mm256_add_epi32(f1, f1)),
                      o2 = _mm256_add_epi32(f2, _mm256_add_epi32(f2, f2));
        const __m256 px = _mm256_i32gather_ps(positions, o0, 4), py = _mm256_i32gather_ps(positions + 1, o0, 4),
                     pz = _mm256_i32gather_ps(positions + 2, o0, 4);
        const __m256 qx = _mm256_i32gather_ps(positions, o1, 4), qy = _mm256_i32gather_ps(positions + 1, o1, 4),
                     qz = _mm256_i32gather_ps(positions + 2, o1, 4);
        const __m256 rx = _mm256_i32gather_ps(positions, o2, 4), ry = _mm256_i32gather_ps(positions + 1, o2, 4),
                     rz = _mm256_i32gather_ps(positions + 2, o2, 4);
        const __m256 ax = _mm256_sub_ps(qx, px), ay = _mm256_sub_ps(qy, py), az = _mm256_sub_ps(qz, pz);
        const __m256 bx = _mm256_sub_ps(rx, px), by = _mm256_sub_ps(ry, py), bz = _mm256_sub_ps(rz, pz);
        const __m256 cx = _mm256_sub_ps(rx, qx), cy = _mm256_sub_ps(ry, qy), cz = _mm256_sub_ps(rz, qz);
        const __m256 nx = _mm256_andnot_ps(sign, _mm256_sub_ps(_mm256_mul_ps(ay, bz), _mm256_mul_ps(az, by)));
        const __m256 ny = _mm256_andnot_ps(sign, _mm256_sub_ps(_mm256_mul_ps(az, bx), _mm256_mul_ps(ax, bz)));
        const __m256 nz = _mm256_andnot_ps(sign, _mm256_sub_ps(_mm256_mul_ps(ax, by), _mm256_mul_ps(ay, bx)));
        __m256 scale = _mm256_mul_ps(ax, ax);
        for (const __m256 e : {ay, az, bx, by, bz, cx, cy, cz}) scale = _mm256_add_ps(scale, _mm256_mul_ps(e, e));
        const __m256 big = _mm256_max_ps(nx, _mm256_max_ps(ny, nz));
        const __m256 clear = _mm256_and_ps(_mm256_cmp_ps(scale, tiny, _CMP_GT_OQ),
                                           _mm256_cmp_ps(big, _mm256_mul_ps(ratio, scale), _CMP_GT_OQ));
        const unsigned cleared = unsigned(_mm256_movemask_ps(clear));
        for (unsigned lane = 0; lane < 8; ++lane) {
            const bool ok = ((distinct >> lane) & 1u) &&
                            (((cleared >> lane) & 1u) ||
                             !detail::is_degenerate_triangle(detail::position(mesh, mesh.indices[3 * (t + lane)]),
                                                             detail::position(mesh, mesh.indices[3 * (t + lane) + 1]),
                                                             detail::position(mesh, mesh.indices[3 * (t + lane) + 2])));
            usable[t + lane] = ok;
            count += ok;
        }
    }
    return count + mark_usable_scalar(mesh, pid, usable, t, last);
}
#endif

uint32_t mark_usable(const TriMesh& mesh, const uint32_t* pid, uint8_t* usable, size_t first, size_t last) {
#if defined(__x86_64__) && defined(__GNUC__)
    static const bool avx2 = __builtin_cpu_supports("avx2");
    if (avx2 && mesh.vertex_count() < (size_t(1) << 31) / 3) return mark_usable_avx2(mesh, pid, usable, first, last);
#endif
    return mark_usable_scalar(mesh, pid, usable, first, last);
}

// Fixed blocks of triangles for the passes that number things in order: block totals, then their prefix
// sums, then each block writes from its offset (the same numbers for any thread count).
constexpr uint32_t kBlock = 16384;

// The usable triangles in triangle order (three distinct positions and a non-zero area) and the positions of
// their corners.
struct KeptTriangles {
    uint32_t faces = 0;
    detail::ScratchArray<uint32_t> triangle;  // per kept face: its triangle in the input mesh
    detail::ScratchArray<uint32_t> pos;       // per corner 3 * face + c: its position
};

// Per block of triangles the usable ones are counted, then each block writes its kept triangles and their
// corners' positions. The large per-triangle, per-corner and per-position arrays of the build are scratch
// arrays (uninitialised, huge pages) wherever every element read has been written first.
KeptTriangles keep_usable_triangles(const TriMesh& mesh, const std::vector<uint32_t>& pid) {
    const size_t tris = mesh.triangle_count();
    const size_t blocks = (tris + kBlock - 1) / kBlock;
    auto block_range = [&](size_t block) {
        return std::pair<size_t, size_t>(block * kBlock, std::min(tris, (block + 1) * kBlock));
    };
    detail::ScratchArray<uint8_t> usable(tris);
    std::vector<uint32_t> block_faces(blocks + 1, 0);
    tbb::parallel_for(tbb::blocked_range<size_t>(0, blocks, 1), [&](const auto& r) {
        for (size_t block = r.begin(); block != r.end(); ++block) {
            const auto [first, last] = block_range(block);
            block_faces[block + 1] = mark_usable(mesh, pid.data(), usable.data(), first, last);
        }
    });
    std::partial_sum(block_faces.begin(), block_faces.end(), block_faces.begin());
    const uint32_t faces = block_faces[blocks];
    KeptTriangles kept{faces, detail::ScratchArray<uint32_t>(faces), detail::ScratchArray<uint32_t>(3 * faces)};
    tbb::parallel_for(tbb::blocked_range<size_t>(0, blocks, 1), [&](const auto& r) {
        for (size_t block = r.begin(); block != r.end(); ++block) {
            const auto [first, last] = block_range(block);
            const uint32_t *const indices = mesh.indices.data(), *const pid_p = pid.data();
            const uint8_t* const usable_p = usable.data();
            uint32_t *const kept_p = kept.triangle.data(), *const pos_p = kept.pos.data();
            uint32_t f = block_faces[block];
            for (size_t t = first; t != last; ++t) {
                if (!usable_p[t]) continue;
                kept_p[f] = uint32_t(t);
                for (int c = 0; c < 3; ++c) pos_p[3 * f + c] = pid_p[indices[3 * t + c]];
                ++f;
            }
            SPECBAKE_ASSERT(f == block_faces[block + 1]);
        }
    });
    return kept;
}

// Corners of each position, in corner order (a counting sort), with the positions of their next and
// previous corners beside them so that the pairing reads each position's corners contiguously.
struct CornersByPosition {
    std::vector<uint32_t> start;                   // per position: its first entry; position_count + 1
    detail::ScratchArray<uint32_t> by_position;    // per entry: the corner
    detail::ScratchArray<uint32_t> around_next;    // per entry: the position of the corner's next corner
    detail::ScratchArray<uint32_t> around_prev;    // per entry: the position of the corner's previous corner
};

// The faces are sorted in two fixed halves side by side: per position, the first half's corners come first.
CornersByPosition sort_corners_by_position(const KeptTriangles& kept, uint32_t position_count) {
    const uint32_t faces = kept.faces, corners = 3 * faces, half = faces / 2;
    const detail::ScratchArray<uint32_t>& pos = kept.pos;
    std::vector<uint32_t> fill[2] = {std::vector<uint32_t>(position_count, 0),
                                     std::vector<uint32_t>(position_count, 0)};
    auto halves = [&](auto&& body) {
        tbb::parallel_invoke([&] { body(0u, 0u, half); }, [&] { body(1u, half, faces); });
    };
    halves([&](uint32_t h, uint32_t first, uint32_t last) {
        uint32_t* const count = fill[h].data();
        const uint32_t* const pos_p = pos.data();
        for (uint32_t k = 3 * first; k != 3 * last; ++k) ++count[pos_p[k]];
    });
    std::vector<uint32_t> start(position_count + 1);
    start[0] = 0;
    for (uint32_t p = 0; p < position_count; ++p) {
        const uint32_t first_half = fill[0][p];
        start[p + 1] = start[p] + first_half + fill[1][p];
        fill[0][p] = start[p];
        fill[1][p] = start[p] + first_half;
    }
    SPECBAKE_ASSERT(start[position_count] == corners);
    detail::ScratchArray<uint32_t> by_position(corners);
    detail::ScratchArray<uint32_t> around_next(corners + 8), around_prev(corners + 8);
    std::fill_n(around_next.data() + corners, 8, kNone);
    std::fill_n(around_prev.data() + corners, 8, kNone);
    halves([&](uint32_t h, uint32_t first, uint32_t last) {
        uint32_t *const fill_p = fill[h].data(), *const by_position_p = by_position.data();
        uint32_t *const next_p = around_next.data(), *const prev_p = around_prev.data();
        const uint32_t* const pos_p = pos.data();
        for (uint32_t f = first; f != last; ++f) {
            const uint32_t p[3] = {pos_p[3 * f], pos_p[3 * f + 1], pos_p[3 * f + 2]};
#pragma GCC unroll 3
            for (uint32_t c = 0; c < 3; ++c) {
                const uint32_t slot = fill_p[p[c]]++;
                by_position_p[slot] = 3 * f + c;
                next_p[slot] = p[c == 2 ? 0 : c + 1];
                prev_p[slot] = p[c == 0 ? 2 : c - 1];
            }
        }
    });
    return {std::move(start), std::move(by_position), std::move(around_next), std::move(around_prev)};
}

// Edge pairing (pair_positions), in parallel over positions.
struct EdgePairing {
    detail::ScratchArray<uint32_t> mate;   // per corner: the halfedge paired with its halfedge, or kNone
    detail::ScratchArray<uint8_t> simple;  // per corner: its edge is simple
    EdgeCounts counts;
};

EdgePairing pair_edges(const CornersByPosition& around, uint32_t corners, uint32_t position_count) {
    EdgePairing pairing{detail::ScratchArray<uint32_t>(corners), detail::ScratchArray<uint8_t>(corners), {}};
    const PairingArrays arrays{around.start.data(), around.by_position.data(), around.around_next.data(),
                               around.around_prev.data(), pairing.mate.data(), pairing.simple.data()};
    pairing.counts = tbb::parallel_reduce(
        tbb::blocked_range<uint32_t>(0, position_count, 2048), EdgeCounts{},
        [&](const tbb::blocked_range<uint32_t>& r, EdgeCounts counts) {
            return pair_positions(arrays, r.begin(), r.end(), counts);
        },
        [](EdgeCounts x, const EdgeCounts& y) {
            x.boundary += y.boundary;
            x.nonmanifold += y.nonmanifold;
            x.not_simple += y.not_simple;
            return x;
        });
    return pairing;
}

// Which faces stay attached to their neighbours: all of them unless some edge is not simple.
struct FaceAttachment {
    std::vector<uint8_t> attached;   // per face when some edge is not simple, else empty (all attached)
    std::vector<uint32_t> detached;  // the detached faces, in order
};

// Faces on a non-simple edge, in triangle order: attached while the edge has no halfedge running their way
// and fewer than two triangles; otherwise detached (and their halfedges unpaired in `pairing.mate`).
// Only when some edge is not simple: usually every face is attached and the scan is skipped.
FaceAttachment attach_faces_on_nonsimple_edges(const KeptTriangles& kept, const CornersByPosition& around,
                                               EdgePairing& pairing) {
    const uint32_t faces = kept.faces;
    const detail::ScratchArray<uint32_t>& pos = kept.pos;
    detail::ScratchArray<uint32_t>& mate = pairing.mate;
    const detail::ScratchArray<uint8_t>& simple = pairing.simple;
    // The halfedges on the position pair {a, b} of halfedge k (a -> b), found among the corners of a, for
    // the rare edges that are not simple.
    auto scan_edge = [&](uint32_t k, uint32_t& total, uint32_t& opposite, uint32_t& partner, uint32_t& lowest) {
        const uint32_t a = pos[k], b = pos[next_corner(k)];
        total = opposite = 0;
        partner = kNone;
        lowest = k;
        for (uint32_t i = around.start[a]; i < around.start[a + 1]; ++i) {
            const uint32_t j = around.by_position[i];
            if (around.around_next[i] == b) {
                ++total;
                lowest = std::min(lowest, j);
            } else if (around.around_prev[i] == b) {
                ++total;
                ++opposite;
                partner = prev_corner(j);
                lowest = std::min(lowest, partner);
            }
        }
    };
    const bool any_not_simple = pairing.counts.not_simple > 0;
    FaceAttachment result{std::vector<uint8_t>(any_not_simple ? faces : 0, 1), {}};
    std::vector<uint8_t>& attached = result.attached;
    struct EdgeState {
        uint32_t first = kNone;
        bool full = false;
    };
    std::unordered_map<uint32_t, EdgeState> state;
    for (uint32_t f = 0; any_not_simple && f < faces; ++f) {
        if (simple[3 * f] && simple[3 * f + 1] && simple[3 * f + 2]) continue;
        uint32_t edge[3] = {kNone, kNone, kNone};
        bool fits = true;
        for (uint32_t c = 0; c < 3 && fits; ++c) {
            const uint32_t k = 3 * f + c;
            if (simple[k]) continue;
            uint32_t total, opposite, partner;
            scan_edge(k, total, opposite, partner, edge[c]);
            const auto it = state.find(edge[c]);
            if (it != state.end() && (it->second.full || pos[it->second.first] != pos[next_corner(k)])) fits = false;
        }
        if (!fits) {
            attached[f] = 0;
            continue;
        }
        for (uint32_t c = 0; c < 3; ++c) {
            const uint32_t k = 3 * f + c;
            if (simple[k]) continue;
            EdgeState& s = state[edge[c]];
            if (s.first == kNone) {
                s.first = k;
            } else {
                mate[k] = s.first;
                mate[s.first] = k;
                s.full = true;
            }
        }
    }
    for (uint32_t f = 0; any_not_simple && f < faces; ++f) {
        if (attached[f]) continue;
        result.detached.push_back(f);
        for (uint32_t k = 3 * f; k < 3 * f + 3; ++k) {
            if (mate[k] != kNone) mate[mate[k]] = kNone;
            mate[k] = kNone;
        }
    }
    return result;
}

// Fans: around a position, corner k's successor is the corner at the same position in the triangle across
// its outgoing halfedge, next_corner(mate[k]); its predecessor is mate[prev_corner(k)]. Each chain or cycle
// of attached corners is one fan and becomes one OpenMesh vertex.
struct FanArrays {
    detail::ScratchArray<uint32_t>& fan;        // per corner: its fan's number at its position
    detail::ScratchArray<uint8_t>& fan_head;    // per corner: it heads its fan
    detail::ScratchArray<uint32_t>& tail_head;  // per corner without successor: its fan's head
};

// Numbers the fans at every position (fan, fan_head, tail_head); returns the fan count per position and
// adds the non-manifold and split vertices to `out`.
detail::ScratchArray<uint32_t> number_fans(const KeptTriangles& kept, const CornersByPosition& around,
                                           const detail::ScratchArray<uint32_t>& mate,
                                           const FaceAttachment& attachment, uint32_t position_count,
                                           const FanArrays& fans_out, HalfEdgeTopology& out) {
    const uint32_t corners = 3 * kept.faces;
    const bool any_detached = !attachment.detached.empty();
    detail::ScratchArray<uint32_t>& fan = fans_out.fan;
    detail::ScratchArray<uint8_t>& fan_head = fans_out.fan_head;
    detail::ScratchArray<uint32_t>& tail_head = fans_out.tail_head;
    // fan and fan_head start as kNone and 0, written in corner order (cheaper than per position).
    tbb::parallel_for(tbb::blocked_range<uint32_t>(0, corners, 65536), [&](const auto& r) {
        std::fill(fan.data() + r.begin(), fan.data() + r.end(), kNone);
        std::fill(fan_head.data() + r.begin(), fan_head.data() + r.end(), uint8_t(0));
    });
    detail::ScratchArray<uint32_t> fan_count(position_count);
    detail::ScratchArray<uint8_t> suspect(position_count);
    tbb::parallel_for(tbb::blocked_range<uint32_t>(0, position_count, 4096), [&](const auto& r) {
        // Local copies: the byte stores below could otherwise alias them and force reloads.
        const uint32_t *const start_p = around.start.data(), *const by_position_p = around.by_position.data();
        const uint32_t* const mate_p = mate.data();
        const uint8_t* const attached_p = attachment.attached.data();
        uint32_t* const fan_p = fan.data();
        const bool detached_any = any_detached;
        for (uint32_t p = r.begin(); p != r.end(); ++p) {
            uint32_t fans = 0;
            bool has_detached = false;
            for (uint32_t i = start_p[p], end = start_p[p + 1]; i < end; ++i) {
                const uint32_t k = by_position_p[i];
                if (detached_any && !attached_p[k / 3]) {
                    has_detached = true;
                    continue;
                }
                if (fan_p[k] != kNone) continue;
                // Forward from k. A cycle comes back to k; its head is k's successor (where the walk back from
                // k, which stops at the corner whose predecessor is k, ends). An open chain is also walked back
                // from k to the corner without a predecessor, its head.
                uint32_t x = k, last = k;
                do {
                    fan_p[x] = fans;
                    last = x;
                    x = mate_p[x] == kNone ? kNone : next_corner(mate_p[x]);
                } while (x != kNone && x != k);
                uint32_t head = k;
                if (x == k) {
                    head = last == k ? k : next_corner(mate_p[k]);
                } else {
                    for (uint32_t back = mate_p[prev_corner(head)]; back != kNone && back != k; back = mate_p[prev_corner(head)]) {
                        head = back;
                        fan_p[head] = fans;
                    }
                    tail_head[last] = head;
                }
                fan_head[head] = 1;
                ++fans;
            }
            fan_count[p] = fans;
            suspect[p] = has_detached || fans > 1;
        }
    });
    for (uint32_t p = 0; p < position_count; ++p) {
        if (!suspect[p]) continue;
        out.nonmanifold_vertices +=
            !link_is_single_fan(kept.pos, &around.by_position[around.start[p]], around.start[p + 1] - around.start[p]);
        if (fan_count[p] > 1) out.split_vertices += fan_count[p] - 1;
    }
    return fan_count;
}

// Element counts of the OpenMesh mesh: vertices per (position, fan), then three per detached face; an edge
// per mate pair or unpaired halfedge (its twin is a boundary halfedge), then three per detached face. Per
// block of faces the edges and attached faces are counted, so that each block numbers from its offsets.
struct ElementCounts {
    ElementCounts(uint32_t position_count, size_t face_blocks)
        : vertex_base(position_count + 1), block_start(face_blocks + 1, {0, 0}) {}
    detail::ScratchArray<uint32_t> vertex_base;                // per position: its first vertex; + 1
    std::vector<std::array<uint32_t, 2>> block_start;          // per face block: first edge, first face
    uint32_t attached_vertices = 0, vertices = 0;
    uint32_t attached_edges = 0, edges = 0;
    uint32_t attached_faces = 0, faces = 0;
};

// Halfedge k opens a new edge unless its mate comes first (kNone is above every corner).
inline bool opens_edge(const uint32_t* mate_p, uint32_t k) { return mate_p[k] > k; }

ElementCounts count_elements(uint32_t faces, const detail::ScratchArray<uint32_t>& fan_count,
                             const detail::ScratchArray<uint32_t>& mate, const FaceAttachment& attachment,
                             uint32_t position_count) {
    const bool any_detached = !attachment.detached.empty();
    const std::vector<uint8_t>& attached = attachment.attached;
    const uint32_t detached_count = uint32_t(attachment.detached.size());
    const size_t face_blocks = (size_t(faces) + kBlock - 1) / kBlock;
    ElementCounts n(position_count, face_blocks);
    n.vertex_base[0] = 0;
    for (uint32_t p = 0; p < position_count; ++p) n.vertex_base[p + 1] = n.vertex_base[p] + fan_count[p];
    n.attached_vertices = n.vertex_base[position_count];
    n.vertices = n.attached_vertices + 3 * detached_count;
    tbb::parallel_for(tbb::blocked_range<size_t>(0, face_blocks, 1), [&](const auto& r) {
        for (size_t block = r.begin(); block != r.end(); ++block) {
            const uint32_t first = uint32_t(block * kBlock);
            const uint32_t last = uint32_t(std::min<size_t>(faces, first + size_t(kBlock)));
            const uint32_t* const mate_p = mate.data();
            uint32_t block_edges = 0, block_faces_attached = 0;
            if (!any_detached) {
                block_faces_attached = last - first;
                for (uint32_t k = 3 * first; k != 3 * last; ++k) block_edges += opens_edge(mate_p, k);
            } else {
                for (uint32_t f = first; f != last; ++f) {
                    if (!attached[f]) continue;
                    ++block_faces_attached;
                    for (uint32_t k = 3 * f; k < 3 * f + 3; ++k) block_edges += opens_edge(mate_p, k);
                }
            }
            n.block_start[block + 1] = {block_edges, block_faces_attached};
        }
    });
    for (size_t block = 0; block < face_blocks; ++block)
        for (int i = 0; i < 2; ++i) n.block_start[block + 1][i] += n.block_start[block][i];
    n.attached_edges = n.block_start[face_blocks][0];
    n.edges = n.attached_edges + 3 * detached_count;
    n.attached_faces = n.block_start[face_blocks][1];
    n.faces = n.attached_faces + detached_count;
    return n;
}

// Sizes the OpenMesh arrays and the per-vertex and per-face outputs to the counts.
void size_mesh(const ElementCounts& n, HalfEdgeTopology& out) {
    using OpenMesh::EdgeHandle;
    using OpenMesh::FaceHandle;
    using OpenMesh::VertexHandle;
    HalfEdgeMesh& m = out.mesh;
    if (n.vertices > 0 && n.edges > 0 && n.faces > 0) {
        // OpenMesh value-initialises its arrays in resize, on one thread (some 60 MB for a million
        // triangles): their storage is reserved first and hinted for huge pages, so resize faults it in
        // 2 MiB at a time. One element of each reaches the reserved storage.
        m.reserve(n.vertices, n.edges, n.faces);
        m.resize(1, 1, 1);
        detail::hint_huge_pages(&m.edge(EdgeHandle(0)), size_t(n.edges) * sizeof(m.edge(EdgeHandle(0))));
        detail::hint_huge_pages(&m.vertex(VertexHandle(0)), size_t(n.vertices) * sizeof(m.vertex(VertexHandle(0))));
        detail::hint_huge_pages(&m.face(FaceHandle(0)), size_t(n.faces) * sizeof(m.face(FaceHandle(0))));
        detail::hint_huge_pages(&m.point(VertexHandle(0)), size_t(n.vertices) * sizeof(HalfEdgeMesh::Point));
    }
    m.resize(n.vertices, n.edges, n.faces);
    detail::reserve_huge_pages(out.vertex_position, n.vertices);
    out.vertex_position.resize(n.vertices);
    detail::reserve_huge_pages(out.face_triangle, n.faces);
    out.face_triangle.resize(n.faces);
}

// The OpenMesh numbering of the attached faces: per corner its halfedge, per corner its vertex (`vertex`
// holds the fan number at the corner's position on entry), per face its OpenMesh face (only when some face
// is detached; the identity otherwise).
struct AttachedNumbering {
    detail::ScratchArray<uint32_t>& halfedge;
    detail::ScratchArray<uint32_t>& vertex;
    detail::ScratchArray<uint32_t>& face_index;
};

void number_attached_faces(const KeptTriangles& kept, const detail::ScratchArray<uint32_t>& mate,
                           const FaceAttachment& attachment, const ElementCounts& n, const AttachedNumbering& to) {
    const uint32_t faces = kept.faces;
    const bool any_detached = !attachment.detached.empty();
    const size_t face_blocks = n.block_start.size() - 1;
    tbb::parallel_for(tbb::blocked_range<size_t>(0, face_blocks, 1), [&](const auto& r) {
        for (size_t block = r.begin(); block != r.end(); ++block) {
            const uint32_t first = uint32_t(block * kBlock);
            const uint32_t last = uint32_t(std::min<size_t>(faces, first + size_t(kBlock)));
            const uint32_t *const mate_p = mate.data(), *const pos_p = kept.pos.data();
            const uint32_t* const base_p = n.vertex_base.data();
            uint32_t *const halfedge_p = to.halfedge.data(), *const vertex_p = to.vertex.data();
            uint32_t* const face_p = to.face_index.data();
            uint32_t e = n.block_start[block][0], face = n.block_start[block][1];
            for (uint32_t f = first; f != last; ++f) {
                if (any_detached && !attachment.attached[f]) continue;
                if (any_detached) face_p[f] = face;
                ++face;
                for (uint32_t k = 3 * f; k < 3 * f + 3; ++k) {
                    vertex_p[k] = base_p[pos_p[k]] + vertex_p[k];
                    if (!opens_edge(mate_p, k)) continue;
                    halfedge_p[k] = 2 * e;
                    if (mate_p[k] != kNone) halfedge_p[mate_p[k]] = 2 * e + 1;
                    ++e;
                }
            }
            SPECBAKE_ASSERT(e == n.block_start[block + 1][0] && face == n.block_start[block + 1][1]);
        }
    });
}

HalfEdgeMesh::Point corner_point(const TriMesh& mesh, const KeptTriangles& kept, uint32_t f, uint32_t c) {
    const float* x = &mesh.positions[3 * size_t(mesh.indices[3 * size_t(kept.triangle[f]) + c])];
    return HalfEdgeMesh::Point(x[0], x[1], x[2]);
}

// One pass per attached face: its halfedges, the boundary halfedges across its unpaired ones, and the
// vertices whose fan it heads. A vertex has one fan, so at most one boundary halfedge out of it: the twin of
// the unpaired halfedge into its head corner (OpenMesh keeps a boundary vertex's halfedge there), which is
// also the boundary successor of the twin into its tail.
void link_attached_faces(const TriMesh& mesh, const KeptTriangles& kept, const detail::ScratchArray<uint32_t>& mate,
                         const FaceAttachment& attachment, const AttachedNumbering& numbering,
                         const FanArrays& fans, HalfEdgeTopology& out) {
    using OpenMesh::FaceHandle;
    using OpenMesh::HalfedgeHandle;
    using OpenMesh::VertexHandle;
    HalfEdgeMesh& m = out.mesh;
    const bool any_detached = !attachment.detached.empty();
    tbb::parallel_for(tbb::blocked_range<uint32_t>(0, kept.faces, 8192), [&](const auto& r) {
        const uint32_t *const halfedge_p = numbering.halfedge.data(), *const vertex_p = numbering.vertex.data();
        const uint32_t* const mate_p = mate.data();
        const uint32_t *const face_p = numbering.face_index.data(), *const kept_p = kept.triangle.data(),
                              *const pos_p = kept.pos.data();
        const uint8_t* const head_p = fans.fan_head.data();
        const uint32_t* const tail_head = fans.tail_head.data();
        uint32_t *const face_triangle = out.face_triangle.data(), *const vertex_position = out.vertex_position.data();
        for (uint32_t f = r.begin(); f != r.end(); ++f) {
            if (any_detached && !attachment.attached[f]) continue;
            const uint32_t face = any_detached ? face_p[f] : f;
            const FaceHandle fh(static_cast<int>(face));
            face_triangle[face] = kept_p[f];
            const uint32_t* const he = halfedge_p + 3 * f;
#pragma GCC unroll 3
            for (uint32_t c = 0; c < 3; ++c) {
                const uint32_t k = 3 * f + c, next = c == 2 ? 0 : c + 1, prev = c == 0 ? 2 : c - 1;
                const HalfedgeHandle h(static_cast<int>(he[c]));
                m.set_vertex_handle(h, VertexHandle(static_cast<int>(vertex_p[3 * f + next])));
                m.set_face_handle(h, fh);
                m.set_next_halfedge_handle(h, HalfedgeHandle(static_cast<int>(he[next])));
                if (mate_p[k] == kNone) {
                    const HalfedgeHandle b(static_cast<int>(he[c] ^ 1u));
                    m.set_vertex_handle(b, VertexHandle(static_cast<int>(vertex_p[k])));
                    m.set_next_halfedge_handle(b, HalfedgeHandle(static_cast<int>(halfedge_p[prev_corner(tail_head[k])] ^ 1u)));
                }
                if (!head_p[k]) continue;
                const uint32_t v = vertex_p[k];
                const uint32_t out_h = mate_p[3 * f + prev] == kNone ? he[prev] ^ 1u : he[c];
                m.set_halfedge_handle(VertexHandle(static_cast<int>(v)), HalfedgeHandle(static_cast<int>(out_h)));
                m.set_point(VertexHandle(static_cast<int>(v)), corner_point(mesh, kept, f, c));
                vertex_position[v] = pos_p[k];
            }
            m.set_halfedge_handle(fh, HalfedgeHandle(static_cast<int>(he[0])));
        }
    });
}

// Each detached face as its own triangle: three fresh vertices, three fresh edges with boundary twins.
void link_detached_faces(const TriMesh& mesh, const KeptTriangles& kept, const FaceAttachment& attachment,
                         const ElementCounts& n, HalfEdgeTopology& out) {
    using OpenMesh::FaceHandle;
    using OpenMesh::HalfedgeHandle;
    using OpenMesh::VertexHandle;
    HalfEdgeMesh& m = out.mesh;
    for (uint32_t d = 0; d < uint32_t(attachment.detached.size()); ++d) {
        const uint32_t f = attachment.detached[d];
        const uint32_t v0 = n.attached_vertices + 3 * d, e0 = n.attached_edges + 3 * d;
        SPECBAKE_ASSERT(v0 + 2 < n.vertices && e0 + 2 < n.edges && n.attached_faces + d < n.faces);
        const FaceHandle fh(static_cast<int>(n.attached_faces + d));
        out.face_triangle[n.attached_faces + d] = kept.triangle[f];
        for (uint32_t c = 0; c < 3; ++c) {
            const HalfedgeHandle h(static_cast<int>(2 * (e0 + c))), b(static_cast<int>(2 * (e0 + c) + 1));
            m.set_vertex_handle(h, VertexHandle(static_cast<int>(v0 + (c + 1) % 3)));
            m.set_vertex_handle(b, VertexHandle(static_cast<int>(v0 + c)));
            m.set_face_handle(h, fh);
            m.set_next_halfedge_handle(h, HalfedgeHandle(static_cast<int>(2 * (e0 + (c + 1) % 3))));
            m.set_next_halfedge_handle(b, HalfedgeHandle(static_cast<int>(2 * (e0 + (c + 2) % 3) + 1)));
            m.set_halfedge_handle(VertexHandle(static_cast<int>(v0 + c)), HalfedgeHandle(static_cast<int>(2 * (e0 + (c + 2) % 3) + 1)));
            m.set_point(VertexHandle(static_cast<int>(v0 + c)), corner_point(mesh, kept, f, c));
            out.vertex_position[v0 + c] = kept.pos[3 * f + c];
        }
        m.set_halfedge_handle(fh, HalfedgeHandle(static_cast<int>(2 * e0)));
    }
}

}  // namespace

HalfEdgeTopology build_halfedge_mesh(const TriMesh& mesh, const WeldedTopology& positions) {
    HalfEdgeTopology out;
    const uint32_t position_count = positions.position_count;
    SPECBAKE_ASSERT(positions.position_id.size() == mesh.vertex_count());
    const KeptTriangles kept = keep_usable_triangles(mesh, positions.position_id);
    out.degenerate_triangles = mesh.triangle_count() - kept.faces;
    const uint32_t corners = 3 * kept.faces;

    CornersByPosition around = sort_corners_by_position(kept, position_count);
    EdgePairing pairing = pair_edges(around, corners, position_count);
    out.boundary_edges = pairing.counts.boundary;
    out.nonmanifold_edges = pairing.counts.nonmanifold;
    const FaceAttachment attachment = attach_faces_on_nonsimple_edges(kept, around, pairing);
    out.detached_faces = attachment.detached.size();

    // The fans live in the storage of around_prev, simple and around_next, no longer read: fewer fresh pages
    // to fault in.
    const FanArrays fans{around.around_prev, pairing.simple, around.around_next};
    const detail::ScratchArray<uint32_t> fan_count =
        number_fans(kept, around, pairing.mate, attachment, position_count, fans, out);

    // The OpenMesh halfedge of each attached corner lives in the storage of by_position (no longer read): one
    // fresh corner-sized array less to fault in; fan[k] becomes the OpenMesh vertex of corner k. The
    // OpenMesh arrays are sized beside the numbering (their sizes are known from the block totals).
    const ElementCounts n = count_elements(kept.faces, fan_count, pairing.mate, attachment, position_count);
    detail::ScratchArray<uint32_t> face_index(attachment.detached.empty() ? 0 : kept.faces);
    const AttachedNumbering numbering{around.by_position, fans.fan, face_index};
    tbb::parallel_invoke([&] { size_mesh(n, out); },
                         [&] { number_attached_faces(kept, pairing.mate, attachment, n, numbering); });

    link_attached_faces(mesh, kept, pairing.mate, attachment, numbering, fans, out);
    link_detached_faces(mesh, kept, attachment, n, out);
    return out;
}

}  // namespace specbake
