// Tessellations of Mitsuba 3's canonical shapes in their object frames, with Mitsuba's uv parameterizations
// (linear uv interpolation across each triangle reproduces them exactly at the vertices).
#include "scene/mesh.h"

#include <algorithm>
#include <cmath>

namespace penumbra {

// rectangle: [-1,1]^2 at z=0, normal +z, uv = ((x+1)/2, (y+1)/2).
TriangleMesh make_rectangle_mesh() {
    TriangleMesh m;
    m.positions = {{-1.f, -1.f, 0.f}, {1.f, -1.f, 0.f}, {1.f, 1.f, 0.f}, {-1.f, 1.f, 0.f}};
    m.uvs = {{0.f, 0.f}, {1.f, 0.f}, {1.f, 1.f}, {0.f, 1.f}};
    m.indices = {0, 1, 2, 0, 2, 3};
    return m;
}

// cube: [-1,1]^3 with 4 vertices per face, outward normals and Mitsuba's per-face uv layout. Each face is
// p(u,v) = n + (2u-1) a + (2v-1) b with outward normal n = cross(b, a); its corners are listed in the uv
// order (0,1), (1,1), (1,0), (0,0) and split into triangles (0,1,2), (3,0,2).
TriangleMesh make_cube_mesh() {
    struct Face {
        Vec3f n, a, b;
    };
    const Face faces[6] = {
        {{0, -1, 0}, {0, 0, 1}, {1, 0, 0}}, {{0, 1, 0}, {-1, 0, 0}, {0, 0, -1}},
        {{1, 0, 0}, {0, 1, 0}, {0, 0, -1}}, {{0, 0, 1}, {0, 1, 0}, {1, 0, 0}},
        {{-1, 0, 0}, {0, 1, 0}, {0, 0, 1}}, {{0, 0, -1}, {0, -1, 0}, {1, 0, 0}},
    };
    const Vec2f corner_uv[4] = {{0, 1}, {1, 1}, {1, 0}, {0, 0}};
    TriangleMesh m;
    for (const Face& f : faces) {
        const uint32_t base = uint32_t(m.positions.size());
        for (const Vec2f& uv : corner_uv) {
            m.positions.push_back(f.n + f.a * (2.f * uv.x - 1.f) + f.b * (2.f * uv.y - 1.f));
            m.normals.push_back(f.n);
            m.uvs.push_back(uv);
        }
        m.indices.insert(m.indices.end(), {base, base + 1, base + 2, base + 3, base, base + 2});
    }
    return m;
}

// disk: unit disk at z=0, normal +z, uv = (r, phi / 2pi) with phi in [0, 2pi). A fan of `segments` triangles;
// each has its own center vertex (uv.y at the middle of its sector) and the seam vertex is duplicated with
// uv.y = 1, so that uv stays continuous inside every triangle.
TriangleMesh make_disk_mesh(int segments) {
    TriangleMesh m;
    for (int j = 0; j <= segments; ++j) {
        // The seam vertex repeats the first exactly (sin(2 pi) is not 0 in float): welded seams are interior
        // edges.
        const float phi = j == segments ? 0.f : 2.f * Pi * float(j) / float(segments);
        m.positions.emplace_back(std::cos(phi), std::sin(phi), 0.f);
        m.uvs.emplace_back(1.f, float(j) / float(segments));
    }
    for (int j = 0; j < segments; ++j) {
        const uint32_t center = uint32_t(m.positions.size());
        m.positions.emplace_back(0.f, 0.f, 0.f);
        m.uvs.emplace_back(0.f, (float(j) + 0.5f) / float(segments));
        m.indices.insert(m.indices.end(), {center, uint32_t(j), uint32_t(j + 1)});
    }
    return m;
}

// sphere: p = center + radius (sin t cos f, sin t sin f, cos t), outward normals, uv = (f / 2pi, t / pi).
// A (rings+1) x (segments+1) grid in (t, f); the seam column is duplicated (u = 0 and u = 1) and each pole
// vertex is repeated per segment with u at the middle of its sector, so the bands at the poles are fans of
// one triangle per segment.
TriangleMesh make_sphere_mesh(const Vec3f& center, float radius, int rings, int segments) {
    TriangleMesh m;
    for (int i = 0; i <= rings; ++i) {
        const float theta = Pi * float(i) / float(rings);
        const bool pole = i == 0 || i == rings;
        for (int j = 0; j <= segments; ++j) {
            const float u = pole ? (float(std::min(j, segments - 1)) + 0.5f) / float(segments)
                                 : float(j) / float(segments);
            // The seam column repeats the first exactly (sin(2 pi) is not 0 in float): welded seams are
            // interior edges.
            const float phi = pole || j == segments ? 0.f : 2.f * Pi * u;
            const Vec3f d(std::sin(theta) * std::cos(phi), std::sin(theta) * std::sin(phi), std::cos(theta));
            m.positions.push_back(center + d * radius);
            m.normals.push_back(d);
            m.uvs.emplace_back(u, float(i) / float(rings));
        }
    }
    const auto v = [&](int i, int j) { return uint32_t(i * (segments + 1) + j); };
    // Each triangle steps in theta, then in phi: cross(dp/dtheta, dp/dphi) points outward.
    for (int i = 0; i < rings; ++i)
        for (int j = 0; j < segments; ++j) {
            if (i == 0) {
                m.indices.insert(m.indices.end(), {v(i, j), v(i + 1, j), v(i + 1, j + 1)});
            } else if (i == rings - 1) {
                m.indices.insert(m.indices.end(), {v(i, j), v(i + 1, j), v(i, j + 1)});
            } else {
                m.indices.insert(m.indices.end(), {v(i, j), v(i + 1, j), v(i + 1, j + 1)});
                m.indices.insert(m.indices.end(), {v(i, j), v(i + 1, j + 1), v(i, j + 1)});
            }
        }
    return m;
}

} // namespace penumbra
