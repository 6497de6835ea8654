#include "diff/edges.h"

#include <algorithm>
#include <map>
#include <tuple>

namespace penumbra {

Vec3f face_normal(const TriangleMesh& m, int32_t f) {
    const uint32_t* i = &m.indices[3 * size_t(f)];
    return cross(m.positions[i[1]] - m.positions[i[0]], m.positions[i[2]] - m.positions[i[0]]);
}

namespace {

// A canonical id per distinct position, so that seams with duplicated vertices still connect their faces.
std::vector<uint32_t> position_ids(const TriangleMesh& m) {
    std::map<std::tuple<float, float, float>, uint32_t> ids;
    std::vector<uint32_t> id(m.positions.size());
    for (size_t v = 0; v < m.positions.size(); ++v) {
        const Vec3f& p = m.positions[v];
        id[v] = ids.try_emplace({p.x, p.y, p.z}, uint32_t(v)).first->second;
    }
    return id;
}

} // namespace

std::vector<Edge> discontinuity_edges(const TriangleMesh& mesh) {
    const std::vector<uint32_t> id = position_ids(mesh);
    struct Half {
        uint32_t a, b; // canonical, a < b
        uint32_t v0, v1;
        int32_t face;
    };
    std::vector<Half> halves;
    halves.reserve(mesh.indices.size());
    for (size_t f = 0; f < mesh.face_count(); ++f)
        for (int k = 0; k < 3; ++k) {
            const uint32_t v0 = mesh.indices[3 * f + k], v1 = mesh.indices[3 * f + (k + 1) % 3];
            const uint32_t a = id[v0], b = id[v1];
            if (a == b) continue; // degenerate
            halves.push_back({std::min(a, b), std::max(a, b), v0, v1, int32_t(f)});
        }
    std::sort(halves.begin(), halves.end(),
              [](const Half& x, const Half& y) { return std::tie(x.a, x.b, x.face) < std::tie(y.a, y.b, y.face); });
    std::vector<Edge> edges;
    for (size_t i = 0; i < halves.size();) {
        size_t j = i + 1;
        while (j < halves.size() && halves[j].a == halves[i].a && halves[j].b == halves[i].b) ++j;
        const Half& h = halves[i];
        if (j - i == 1) {
            edges.push_back({h.v0, h.v1, h.face, -1});
        } else if (j - i == 2) {
            // Coplanar faces (to float precision: the apex of one lies in the other's plane within 1e-6 of its
            // distance) make a flat edge. Fine tessellations have dihedral angles far below what a test on the
            // normals' cosine resolves (near the poles of a uv sphere, a few hundredths of a degree).
            const int32_t f1 = halves[i + 1].face;
            const uint32_t* t1 = &mesh.indices[3 * size_t(f1)];
            const Vec3f a = mesh.positions[h.v0], n0 = face_normal(mesh, h.face);
            float distance = 0.f, extent = 0.f;
            for (int k = 0; k < 3; ++k) {
                const Vec3f q = mesh.positions[t1[k]] - a;
                distance = std::max(distance, std::abs(dot(n0, q)));
                extent = std::max(extent, norm(q));
            }
            if (distance > 1e-6f * extent * norm(n0)) edges.push_back({h.v0, h.v1, h.face, f1});
        } else {
            // Non-manifold: every face pair may be a discontinuity; keep each face as a boundary.
            for (size_t k = i; k < j; ++k) edges.push_back({halves[k].v0, halves[k].v1, halves[k].face, -1});
        }
        i = j;
    }
    return edges;
}

bool is_silhouette(const TriangleMesh& mesh, const Edge& e, const Vec3f& eye) {
    if (e.f1 < 0) return true;
    const Vec3f to_eye = eye - mesh.positions[e.v0];
    return (dot(face_normal(mesh, e.f0), to_eye) > 0.f) !=
           (dot(face_normal(mesh, e.f1), to_eye) > 0.f);
}

bool is_silhouette_parallel(const TriangleMesh& mesh, const Edge& e, const Vec3f& forward) {
    if (e.f1 < 0) return true;
    return (dot(face_normal(mesh, e.f0), forward) < 0.f) !=
           (dot(face_normal(mesh, e.f1), forward) < 0.f);
}

} // namespace penumbra
