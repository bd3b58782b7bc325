#include "mesh/curvature_frames.h"

#include <tbb/parallel_for.h>

#include <algorithm>

namespace specbake::detail {

void group_frame(const float normal[3], Vec3d& n, Vec3d& u, Vec3d& v) {
    const Vec3d nv(normal[0], normal[1], normal[2]);
    const double len = nv.norm();
    n = len > 0.0 ? Vec3d(nv / len) : Vec3d(0.0, 0.0, 1.0);
    orthonormal_basis(n, u, v);
}

GroupFrames make_group_frames(const TriMesh& mesh, const WeldedTopology& topology) {
    GroupFrames frames;
    frames.n.resize(topology.group_count);
    frames.u.resize(topology.group_count);
    frames.v.resize(topology.group_count);
    tbb::parallel_for(tbb::blocked_range<size_t>(0, topology.group_count, 4096), [&](const auto& r) {
        for (size_t g = r.begin(); g != r.end(); ++g)
            group_frame(&mesh.normals[3 * size_t(topology.group_vertex[g])], frames.n[g], frames.u[g], frames.v[g]);
    });
    return frames;
}

GroupCorners group_corners(const TriMesh& mesh, const WeldedTopology& topology) {
    // A stable counting sort in a fixed number of slices of the corner range: each slice counts its corners
    // per group, a group's corners are then placed slice by slice, so every group lists its corners in
    // increasing order whatever the number of threads that ran the slices. The offsets are a two-level scan
    // over blocks of groups, so no step runs over all groups on one thread.
    const size_t corners = mesh.indices.size();
    const uint32_t groups = topology.group_count;
    const uint32_t* group_id = topology.group_id.data();
    const uint32_t* indices = mesh.indices.data();
    constexpr size_t kSlices = 4;
    const size_t slice = (corners + kSlices - 1) / kSlices;
    ScratchArray<uint32_t> count(kSlices * size_t(groups));  // slice s, group g at [s * groups + g]
    tbb::parallel_for(size_t(0), kSlices, [&](size_t s) {
        uint32_t* c = &count[s * groups];
        std::fill(c, c + groups, 0u);
        for (size_t k = s * slice; k < std::min(corners, (s + 1) * slice); ++k) ++c[group_id[indices[k]]];
    });
    GroupCorners out{ScratchArray<uint32_t>(size_t(groups) + 1), ScratchArray<uint32_t>(corners)};
    constexpr uint32_t kBlock = 16384;
    const uint32_t blocks = (groups + kBlock - 1) / kBlock;
    std::vector<uint32_t> block_total(blocks + 1, 0);
    tbb::parallel_for(uint32_t(0), blocks, [&](uint32_t b) {
        uint32_t total = 0;
        for (uint32_t g = b * kBlock; g < std::min(groups, (b + 1) * kBlock); ++g)
            for (size_t s = 0; s < kSlices; ++s) total += count[s * groups + g];
        block_total[b + 1] = total;
    });
    for (uint32_t b = 0; b < blocks; ++b) block_total[b + 1] += block_total[b];
    tbb::parallel_for(uint32_t(0), blocks, [&](uint32_t b) {
        uint32_t total = block_total[b];
        for (uint32_t g = b * kBlock; g < std::min(groups, (b + 1) * kBlock); ++g) {
            out.start[g] = total;
            for (size_t s = 0; s < kSlices; ++s) {
                const uint32_t n = count[s * groups + g];
                count[s * groups + g] = total;  // now the slice's first slot in group g
                total += n;
            }
        }
    });
    out.start[groups] = block_total[blocks];
    tbb::parallel_for(size_t(0), kSlices, [&](size_t s) {
        uint32_t* fill = &count[s * groups];
        for (size_t k = s * slice; k < std::min(corners, (s + 1) * slice); ++k)
            out.order[fill[group_id[indices[k]]]++] = uint32_t(k);
    });
    return out;
}

bool skip_triangle(const TriMesh& mesh, const WeldedTopology& topology, size_t t) {
    const uint32_t* f = &mesh.indices[3 * t];
    const uint32_t a = topology.position_id[f[0]], b = topology.position_id[f[1]], c = topology.position_id[f[2]];
    if (a == b || b == c || a == c) return true;
    return is_degenerate_triangle(position(mesh, f[0]), position(mesh, f[1]), position(mesh, f[2]));
}

GroupPrincipal principal_curvatures(const Shape2& s, const Vec3d& u, const Vec3d& v) {
    GroupPrincipal p{};
    const double mean = 0.5 * (s.a + s.c);
    const double half_diff = 0.5 * (s.a - s.c);
    const double radius = std::sqrt(half_diff * half_diff + s.b * s.b);
    const double hi = mean + radius, lo = mean - radius;
    const bool hi_first = std::abs(hi) >= std::abs(lo);
    p.k1 = hi_first ? hi : lo;
    p.k2 = hi_first ? lo : hi;
    // Eigenvector of k1 from whichever row of (S - k1 I) is better conditioned.
    const double x1 = s.b, y1 = p.k1 - s.a;  // from row 1: (a - k1) x + b y = 0
    const double x2 = p.k1 - s.c, y2 = s.b;  // from row 2: b x + (c - k1) y = 0
    double x = x1, y = y1;
    if (x2 * x2 + y2 * y2 > x1 * x1 + y1 * y1) {
        x = x2;
        y = y2;
    }
    const double len = std::sqrt(x * x + y * y);
    if (!(len > 1e-12 * std::max(std::abs(p.k1), 1e-300))) {
        x = 1.0;
        y = 0.0;
    } else {
        x /= len;
        y /= len;
    }
    for (int k = 0; k < 3; ++k) p.dir[k] = x * u[k] + y * v[k];
    return p;
}

void vertex_curvature_at(const TriMesh& mesh, const WeldedTopology& topology, size_t v, const GroupPrincipal& p,
                         float out[4]) {
    const float* normals = mesh.normals.data();
    const float* tangents = mesh.tangents.data();
    double n[3] = {normals[3 * v], normals[3 * v + 1], normals[3 * v + 2]};
    const double n2 = n[0] * n[0] + n[1] * n[1] + n[2] * n[2];
    if (n2 > 0.0) {
        const double len = std::sqrt(n2);
        for (double& x : n) x /= len;
    } else {
        Vec3d gn, gu, gv;
        group_frame(&normals[3 * size_t(topology.group_vertex[topology.group_id[v]])], gn, gu, gv);
        for (int k = 0; k < 3; ++k) n[k] = gn[k];
    }
    // T orthogonalised against N (a fixed perpendicular when T is along N), B = cross(N, T) * w.
    double t[3] = {tangents[4 * v], tangents[4 * v + 1], tangents[4 * v + 2]};
    const double nt = n[0] * t[0] + n[1] * t[1] + n[2] * t[2];
    for (int k = 0; k < 3; ++k) t[k] -= nt * n[k];
    const double tl = std::sqrt(t[0] * t[0] + t[1] * t[1] + t[2] * t[2]);
    if (tl > 1e-12) {
        for (double& x : t) x /= tl;
    } else {
        Vec3d bt, bb;
        orthonormal_basis(Vec3d(n[0], n[1], n[2]), bt, bb);
        for (int k = 0; k < 3; ++k) t[k] = bt[k];
    }
    const double sign = tangents[4 * v + 3] < 0.0f ? -1.0 : 1.0;
    const double b[3] = {sign * (n[1] * t[2] - n[2] * t[1]), sign * (n[2] * t[0] - n[0] * t[2]),
                         sign * (n[0] * t[1] - n[1] * t[0])};
    double dx = p.dir[0] * t[0] + p.dir[1] * t[1] + p.dir[2] * t[2];
    double dy = p.dir[0] * b[0] + p.dir[1] * b[1] + p.dir[2] * b[2];
    const double dl = std::sqrt(dx * dx + dy * dy);
    if (dl > 1e-12) {
        dx /= dl;
        dy /= dl;
    } else {
        dx = 1.0;
        dy = 0.0;
    }
    out[0] = float(p.k1);
    out[1] = float(p.k2);
    out[2] = float(dx);
    out[3] = float(dy);
}

VertexCurvature vertex_curvature_from_principal(const TriMesh& mesh, const WeldedTopology& topology,
                                                const GroupPrincipal* principal) {
    VertexCurvature out;
    out.values.resize(4 * mesh.vertex_count());
    tbb::parallel_for(tbb::blocked_range<size_t>(0, mesh.vertex_count(), 8192), [&](const auto& r) {
        for (size_t v = r.begin(); v != r.end(); ++v)
            vertex_curvature_at(mesh, topology, v, principal[topology.group_id[v]], &out.values[4 * v]);
    });
    return out;
}

VertexCurvature vertex_curvature_from_groups(const TriMesh& mesh, const WeldedTopology& topology,
                                             const GroupFrames& frames, const std::vector<Shape2>& shape) {
    std::vector<GroupPrincipal> principal(topology.group_count);
    tbb::parallel_for(tbb::blocked_range<size_t>(0, topology.group_count, 4096), [&](const auto& r) {
        for (size_t g = r.begin(); g != r.end(); ++g)
            principal[g] = principal_curvatures(shape[g], frames.u[g], frames.v[g]);
    });
    return vertex_curvature_from_principal(mesh, topology, principal.data());
}

}  // namespace specbake::detail
