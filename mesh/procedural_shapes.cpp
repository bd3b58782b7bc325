#include "mesh/procedural_shapes.h"

#include <cmath>
#include <functional>
#include <map>
#include <random>

#include "mesh/mesh_math.h"

namespace specbake {
namespace {

using detail::Vec3d;

// A parametric surface over (u, v) in [0, 1]^2: position and unit normal. u wraps around (seam at 0/1).
struct Surface {
    std::function<Vec3d(double, double)> position;
    std::function<Vec3d(double, double)> normal;
    bool poles = false;   // rows v = 0 and v = 1 collapse to one point each (sphere, ellipsoid)
    bool wrap_v = false;  // v wraps too (torus): row v = 1 repeats row v = 0
};

void push_vertex(TriMesh& m, const Surface& s, double u, double v, const Vec3d& p, const Vec3d& n) {
    // Tangent along dP/du; at a pole dP/du vanishes, so it is taken just off the pole on the same meridian.
    const double h = 1e-6;
    const double vs = std::clamp(v, 1e-4, 1.0 - 1e-4);
    const Vec3d pu = s.position(u + h, vs) - s.position(u - h, vs);
    const Vec3d pv = s.position(u, std::min(vs + h, 1.0)) - s.position(u, std::max(vs - h, 0.0));
    Vec3d t = (pu - pu.dot(n) * n).normalized();
    // glTF: the bitangent cross(N, T) * w points along decreasing v.
    const double w = n.cross(t).dot(-pv) < 0.0 ? -1.0 : 1.0;
    for (int k = 0; k < 3; ++k) {
        m.positions.push_back(float(p[k]));
        m.normals.push_back(float(n[k]));
        m.tangents.push_back(float(t[k]));
    }
    m.tangents.push_back(float(w));
    m.uv0.push_back(float(u));
    m.uv0.push_back(float(v));
}

TriMesh make_grid(const Surface& s, int cols, int rows, float jitter, uint32_t seed) {
    TriMesh m;
    std::mt19937 rng(seed);
    std::uniform_real_distribution<double> offset(-double(jitter), double(jitter));
    const double du = 1.0 / cols, dv = 1.0 / rows;

    // Winding chosen so triangles face along the given normal.
    const Vec3d pu = s.position(0.31 + 1e-5, 0.37) - s.position(0.31 - 1e-5, 0.37);
    const Vec3d pv = s.position(0.31, 0.37 + 1e-5) - s.position(0.31, 0.37 - 1e-5);
    const bool flip = pu.cross(pv).dot(s.normal(0.31, 0.37)) < 0.0;

    // Parameters of every grid point; interior points jittered, seam and boundary rows/columns kept exact.
    std::vector<double> gu((cols + 1) * (rows + 1)), gv(gu.size());
    for (int j = 0; j <= rows; ++j)
        for (int i = 0; i <= cols; ++i) {
            double u = i * du, v = j * dv;
            const bool edge_row = j == 0 || j == rows;
            if (i > 0 && i < cols && !edge_row && jitter > 0.0f) {
                u += offset(rng) * du;
                v += offset(rng) * dv;
            } else if (i > 0 && i < cols && edge_row && s.wrap_v && jitter > 0.0f) {
                u += offset(rng) * du;  // torus seam row: jitter along it, row 0 and row `rows` stay equal below
            }
            gu[j * (cols + 1) + i] = u;
            gv[j * (cols + 1) + i] = v;
        }
    if (s.wrap_v)
        for (int i = 0; i <= cols; ++i) gu[rows * (cols + 1) + i] = gu[i];

    std::vector<uint32_t> id(gu.size(), 0);
    std::vector<Vec3d> pos(gu.size()), nrm(gu.size());
    for (int j = 0; j <= rows; ++j)
        for (int i = 0; i <= cols; ++i) {
            const size_t k = j * (cols + 1) + i;
            // Seams reuse the evaluated values of the other side so welded positions match bit for bit.
            if (i == cols) {
                pos[k] = pos[k - cols];
                nrm[k] = nrm[k - cols];
            } else if (s.wrap_v && j == rows) {
                pos[k] = pos[i];
                nrm[k] = nrm[i];
            } else {
                pos[k] = s.position(gu[k], gv[k]);
                nrm[k] = s.normal(gu[k], gv[k]);
            }
        }

    auto tri = [&](uint32_t a, uint32_t b, uint32_t c) {
        if (flip) std::swap(b, c);
        m.indices.insert(m.indices.end(), {a, b, c});
    };
    const int first_row = s.poles ? 1 : 0, last_row = s.poles ? rows - 1 : rows;
    for (int j = first_row; j <= last_row; ++j)
        for (int i = 0; i <= cols; ++i) {
            const size_t k = j * (cols + 1) + i;
            id[k] = uint32_t(m.vertex_count());
            push_vertex(m, s, gu[k], gv[k], pos[k], nrm[k]);
        }
    for (int j = first_row; j < last_row; ++j)
        for (int i = 0; i < cols; ++i) {
            const uint32_t a = id[j * (cols + 1) + i], b = id[j * (cols + 1) + i + 1];
            const uint32_t c = id[(j + 1) * (cols + 1) + i + 1], d = id[(j + 1) * (cols + 1) + i];
            tri(a, b, c);
            tri(a, c, d);
        }
    if (s.poles) {
        // One pole vertex per segment (its own u and tangent), as UV-sphere exporters write them.
        for (int i = 0; i < cols; ++i) {
            const double u = (i + 0.5) * du;
            const uint32_t top = uint32_t(m.vertex_count());
            push_vertex(m, s, u, 0.0, s.position(0.0, 0.0), s.normal(0.0, 0.0));
            tri(top, id[1 * (cols + 1) + i + 1], id[1 * (cols + 1) + i]);
            const uint32_t bottom = uint32_t(m.vertex_count());
            push_vertex(m, s, u, 1.0, s.position(0.0, 1.0), s.normal(0.0, 1.0));
            tri(bottom, id[(rows - 1) * (cols + 1) + i], id[(rows - 1) * (cols + 1) + i + 1]);
        }
    }
    return m;
}

}  // namespace

TriMesh make_ellipsoid(float a, float b, float c, int segments, int rings, float jitter, uint32_t seed) {
    Surface s;
    s.poles = true;
    const double A = a, B = b, C = c;
    s.position = [=](double u, double v) {
        const double phi = 2.0 * M_PI * u, theta = M_PI * v;
        return Vec3d(A * std::sin(theta) * std::cos(phi), B * std::sin(theta) * std::sin(phi), C * std::cos(theta));
    };
    s.normal = [=](double u, double v) {
        const double phi = 2.0 * M_PI * u, theta = M_PI * v;
        // Gradient of x^2/a^2 + y^2/b^2 + z^2/c^2 at the point.
        return Vec3d(std::sin(theta) * std::cos(phi) / A, std::sin(theta) * std::sin(phi) / B, std::cos(theta) / C)
            .normalized();
    };
    TriMesh m = make_grid(s, segments, rings, jitter, seed);
    m.name = "ellipsoid";
    return m;
}

TriMesh make_uv_sphere(float radius, int segments, int rings, float jitter, uint32_t seed) {
    TriMesh m = make_ellipsoid(radius, radius, radius, segments, rings, jitter, seed);
    m.name = "uv_sphere";
    return m;
}

TriMesh make_cylinder(float radius, float height, int segments, int rows, float jitter, uint32_t seed) {
    Surface s;
    const double R = radius, H = height;
    s.position = [=](double u, double v) {
        const double phi = 2.0 * M_PI * u;
        return Vec3d(R * std::cos(phi), R * std::sin(phi), H * (0.5 - v));
    };
    s.normal = [](double u, double) {
        const double phi = 2.0 * M_PI * u;
        return Vec3d(std::cos(phi), std::sin(phi), 0.0);
    };
    TriMesh m = make_grid(s, segments, rows, jitter, seed);
    m.name = "cylinder";
    return m;
}

TriMesh make_torus(float major_radius, float minor_radius, int segments, int sides, float jitter, uint32_t seed) {
    Surface s;
    s.wrap_v = true;
    const double R = major_radius, r = minor_radius;
    s.position = [=](double u, double v) {
        const double phi = 2.0 * M_PI * u, psi = 2.0 * M_PI * v;
        return Vec3d((R + r * std::cos(psi)) * std::cos(phi), (R + r * std::cos(psi)) * std::sin(phi),
                     r * std::sin(psi));
    };
    s.normal = [](double u, double v) {
        const double phi = 2.0 * M_PI * u, psi = 2.0 * M_PI * v;
        return Vec3d(std::cos(psi) * std::cos(phi), std::cos(psi) * std::sin(phi), std::sin(psi));
    };
    TriMesh m = make_grid(s, segments, sides, jitter, seed);
    m.name = "torus";
    return m;
}

TriMesh make_icosphere(float radius, int subdivisions) {
    const double t = (1.0 + std::sqrt(5.0)) / 2.0;
    std::vector<Vec3d> p = {{-1, t, 0}, {1, t, 0},  {-1, -t, 0}, {1, -t, 0}, {0, -1, t},  {0, 1, t},
                            {0, -1, -t}, {0, 1, -t}, {t, 0, -1},  {t, 0, 1},  {-t, 0, -1}, {-t, 0, 1}};
    for (Vec3d& q : p) q.normalize();
    std::vector<uint32_t> f = {0, 11, 5, 0, 5,  1, 0, 1, 7, 0, 7,  10, 0, 10, 11, 1, 5, 9, 5, 11,
                               4, 11, 10, 2, 10, 7, 6, 7, 1, 8, 3, 9, 4, 3, 4,  2, 3, 2, 6, 3,
                               6, 8, 3, 8,  9, 4, 9, 5, 2, 4, 11, 6, 2, 10, 8, 6, 7, 9, 8, 1};
    for (int s = 0; s < subdivisions; ++s) {
        std::map<std::pair<uint32_t, uint32_t>, uint32_t> midpoint;
        auto mid = [&](uint32_t a, uint32_t b) {
            const auto key = std::minmax(a, b);
            auto it = midpoint.find(key);
            if (it != midpoint.end()) return it->second;
            p.push_back((p[a] + p[b]).normalized());
            return midpoint[key] = uint32_t(p.size() - 1);
        };
        std::vector<uint32_t> g;
        for (size_t k = 0; k < f.size(); k += 3) {
            const uint32_t a = f[k], b = f[k + 1], c = f[k + 2];
            const uint32_t ab = mid(a, b), bc = mid(b, c), ca = mid(c, a);
            g.insert(g.end(), {a, ab, ca, b, bc, ab, c, ca, bc, ab, bc, ca});
        }
        f.swap(g);
    }
    TriMesh m;
    m.name = "icosphere";
    for (const Vec3d& n : p) {
        Vec3d tan = Vec3d(0, 0, 1).cross(n);
        tan = tan.norm() > 1e-9 ? Vec3d(tan.normalized()) : Vec3d(1, 0, 0);
        for (int k = 0; k < 3; ++k) {
            m.positions.push_back(float(radius * n[k]));
            m.normals.push_back(float(n[k]));
            m.tangents.push_back(float(tan[k]));
        }
        m.tangents.push_back(1.0f);
    }
    m.indices = f;
    return m;
}

TriMesh make_flat_cube(float h) {
    TriMesh m;
    m.name = "flat_cube";
    const int axes[6][3] = {{0, 1, 2}, {0, 1, 2}, {1, 2, 0}, {1, 2, 0}, {2, 0, 1}, {2, 0, 1}};
    for (int face = 0; face < 6; ++face) {
        const double sign = face % 2 == 0 ? 1.0 : -1.0;
        Vec3d n = Vec3d::Zero(), a = Vec3d::Zero(), b = Vec3d::Zero();
        n[axes[face][2]] = sign;
        a[axes[face][0]] = 1.0;
        b = n.cross(a);
        const uint32_t base = uint32_t(m.vertex_count());
        const double corners[4][2] = {{-1, -1}, {1, -1}, {1, 1}, {-1, 1}};
        for (const auto& c : corners) {
            const Vec3d p = h * (n + c[0] * a + c[1] * b);
            for (int k = 0; k < 3; ++k) {
                m.positions.push_back(float(p[k]));
                m.normals.push_back(float(n[k]));
                m.tangents.push_back(float(a[k]));
            }
            m.tangents.push_back(-1.0f);  // B = cross(N, T) * w = -b points along decreasing v (uv below)
            m.uv0.push_back(float(0.5 * (c[0] + 1.0)));
            m.uv0.push_back(float(0.5 * (c[1] + 1.0)));
        }
        m.indices.insert(m.indices.end(), {base, base + 1, base + 2, base, base + 2, base + 3});
    }
    return m;
}

TriMesh make_plane(float size, int n) {
    TriMesh m;
    m.name = "plane";
    for (int j = 0; j <= n; ++j)
        for (int i = 0; i <= n; ++i) {
            const float x = size * float(i) / float(n), y = size * float(j) / float(n);
            m.positions.insert(m.positions.end(), {x, y, 0.0f});
            m.normals.insert(m.normals.end(), {0.0f, 0.0f, 1.0f});
            m.tangents.insert(m.tangents.end(), {1.0f, 0.0f, 0.0f, 1.0f});
            m.uv0.insert(m.uv0.end(), {float(i) / float(n), 1.0f - float(j) / float(n)});
        }
    for (int j = 0; j < n; ++j)
        for (int i = 0; i < n; ++i) {
            const uint32_t a = uint32_t(j * (n + 1) + i), b = a + 1, c = a + uint32_t(n) + 2, d = a + uint32_t(n) + 1;
            m.indices.insert(m.indices.end(), {a, b, c, a, c, d});
        }
    return m;
}

void scale_mesh(TriMesh& mesh, float s) {
    for (float& x : mesh.positions) x *= s;
}

}  // namespace specbake
