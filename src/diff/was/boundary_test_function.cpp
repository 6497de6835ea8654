#include "diff/was/boundary_test_function.h"

#include "core/error.h"

#include <algorithm>
#include <numeric>
#include <tuple>

namespace penumbra {

namespace {

// One id per distinct position, the smallest vertex index that has it (sorting by position: a map of 440k
// vertices costs more than the implicit-edge search of the hedge).
std::vector<uint32_t> canonical_ids(const TriangleMesh& mesh) {
    const auto position = [&](uint32_t v) {
        const Vec3f& p = mesh.positions[v];
        return std::tuple(p.x, p.y, p.z);
    };
    std::vector<uint32_t> order(mesh.positions.size());
    std::iota(order.begin(), order.end(), 0u);
    std::sort(order.begin(), order.end(),
              [&](uint32_t a, uint32_t b) { return std::pair(position(a), a) < std::pair(position(b), b); });
    std::vector<uint32_t> id(mesh.positions.size());
    for (size_t k = 0; k < order.size(); ++k)
        id[order[k]] = k > 0 && position(order[k]) == position(order[k - 1]) ? id[order[k - 1]] : order[k];
    return id;
}

// Whether the shading normal jumps across edge e: a flat-shaded shape (face normals, which differ across a
// discontinuity edge between faces) or split vertex normals (a hard edge of a smooth-shaded mesh).
bool is_crease(const Shape& shape, const std::vector<uint32_t>& canonical, const Edge& e) {
    const TriangleMesh& mesh = shape.mesh;
    if (e.f1 < 0) return false;
    if (mesh.normals.empty() || shape.face_normals) return true;
    const auto corner = [&](int32_t f, uint32_t v) {
        for (int k = 0; k < 3; ++k) {
            const uint32_t u = mesh.indices[3 * size_t(f) + size_t(k)];
            if (canonical[u] == canonical[v]) return u;
        }
        return v;
    };
    for (const uint32_t v : {e.v0, e.v1})
        if (dot(mesh.normals[corner(e.f0, v)], mesh.normals[corner(e.f1, v)]) < 0.9999f) return true;
    return false;
}

} // namespace

BoundaryTest::BoundaryTest(const Scene& scene, float spread, bool implicit_edges) : spread_(spread) {
    if (implicit_edges) implicit_ = std::make_unique<ImplicitEdges>(scene);
    for (const auto& shape : scene.shapes) {
        const TriangleMesh& mesh = shape->mesh;
        MeshEdges m;
        m.canonical = canonical_ids(mesh);
        m.edges = discontinuity_edges(mesh);
        m.crease.resize(m.edges.size());
        for (size_t k = 0; k < m.edges.size(); ++k)
            m.crease[k] = is_crease(*shape, m.canonical, m.edges[k]);
        const size_t n = mesh.vertex_count();
        m.offsets.assign(n + 1, 0);
        for (const Edge& e : m.edges) {
            ++m.offsets[m.canonical[e.v0] + 1];
            ++m.offsets[m.canonical[e.v1] + 1];
        }
        for (size_t v = 0; v < n; ++v)
            m.offsets[v + 1] += m.offsets[v];
        m.ids.resize(m.offsets[n]);
        std::vector<uint32_t> fill(m.offsets.begin(), m.offsets.end() - 1);
        for (size_t k = 0; k < m.edges.size(); ++k) {
            m.ids[fill[m.canonical[m.edges[k].v0]]++] = uint32_t(k);
            m.ids[fill[m.canonical[m.edges[k].v1]]++] = uint32_t(k);
        }
        // Area-weighted sum of the face normals around each position ("the average normal of all adjacent
        // faces").
        m.normals.assign(n, Vec3f(0.f));
        for (size_t f = 0; f < mesh.face_count(); ++f) {
            const Vec3f nf = face_normal(mesh, int32_t(f));
            for (int k = 0; k < 3; ++k)
                m.normals[m.canonical[mesh.indices[3 * f + k]]] += nf;
        }
        for (Vec3f& nv : m.normals)
            if (norm(nv) > 0.f) nv = normalize(nv);
        meshes_.emplace(shape.get(), std::move(m));
    }
}

const BoundaryTest::MeshEdges& BoundaryTest::edges_of(const Shape& shape) const {
    const auto it = meshes_.find(&shape);
    if (it == meshes_.end())
        throw Error("BoundaryTest: shape '" + shape.id + "' is not in the scene it was built for");
    return it->second;
}

float BoundaryTest::normal_value(const MeshEdges& m, uint32_t v, const Vec3f& direction) const {
    const float cos_theta = dot(direction, m.normals[m.canonical[v]]);
    const float sin2 = std::max(0.f, 1.f - cos_theta * cos_theta);
    return (1.f - sin2) / (1.f - (1.f - spread_) * sin2);
}

bool BoundaryTest::on_boundary(const Shape& shape, const MeshEdges& m, uint32_t v, uint32_t w,
                               const Vec3f& origin, bool creases, bool& to_w) const {
    const uint32_t c = m.canonical[v], cw = m.canonical[w];
    bool any = false;
    for (uint32_t k = m.offsets[c]; k < m.offsets[c + 1]; ++k) {
        const Edge& e = m.edges[m.ids[k]];
        if (!(creases && m.crease[m.ids[k]]) && !is_silhouette(shape.mesh, e, origin)) continue;
        any = true;
        if (m.canonical[e.v0] == cw || m.canonical[e.v1] == cw) to_w = true;
    }
    return any;
}

float BoundaryTest::vertex_value(const Shape& shape, uint32_t v, const Vec3f& origin,
                                 const Vec3f& direction) const {
    const MeshEdges& m = edges_of(shape);
    bool unused = false;
    return on_boundary(shape, m, v, v, origin, false, unused) ? 0.f : normal_value(m, v, direction);
}

namespace {

// The angle at `o` between the directions to `p` and to the point of segment [a, b] nearest to p.
float angle_to_segment(const Vec3f& o, const Vec3f& p, const Vec3f& a, const Vec3f& b) {
    const Vec3f ab = b - a;
    const float len2 = dot(ab, ab);
    const float t = len2 > 0.f ? std::clamp(dot(p - a, ab) / len2, 0.f, 1.f) : 0.f;
    const Vec3f u = normalize(p - o), q = normalize(a + ab * t - o);
    return 2.f * std::asin(std::min(1.f, 0.5f * norm(u - q)));
}

} // namespace

float BoundaryTest::implicit_edge_factor(const SurfaceInteraction3f& hit, const Vec3f& origin,
                                         const Vec3f& direction) const {
    if (!implicit_) return 1.f;
    return spread_map(implicit_->nearest(hit, origin, direction).sine);
}

float BoundaryTest::operator()(const SurfaceInteraction3f& hit, const Vec3f& origin, const Vec3f& direction,
                               float scale) const {
    if (!hit.is_valid()) return 1.f;
    const Shape& shape = *hit.shape;
    const uint32_t* i = &shape.mesh.indices[3 * size_t(hit.prim_index)];
    const float b[3] = {1.f - hit.bary.x - hit.bary.y, hit.bary.x, hit.bary.y};
    if (!(scale > 0.f)) {
        float B = 0.f;
        for (int k = 0; k < 3; ++k)
            B += b[k] * vertex_value(shape, i[k], origin, direction);
        return B * implicit_edge_factor(hit, origin, direction);
    }
    const MeshEdges& m = edges_of(shape);
    float B = 0.f;
    for (int k = 0; k < 3; ++k)
        B += b[k] * normal_value(m, i[k], direction);
    // The nearest boundary point on the triangle: a silhouette or open edge of it, or a corner on one.
    float r = Infinity;
    const Vec3f* p = shape.mesh.positions.data();
    for (int k = 0; k < 3; ++k) {
        const uint32_t v = i[k], w = i[(k + 1) % 3];
        bool edge = false;
        if (!on_boundary(shape, m, v, w, origin, true, edge)) continue;
        r = std::min(r, edge ? angle_to_segment(origin, hit.p, p[v], p[w]) : angle_to_segment(origin, hit.p, p[v], p[v]));
    }
    // An implicit edge inside the triangle (u: the sine of the angle to it).
    if (implicit_) {
        const NearestSegment nearest = implicit_->nearest(hit, origin, direction);
        if (nearest.segment) r = std::min(r, std::asin(std::min(1.f, nearest.sine)));
    }
    if (r < Infinity) B = std::min(B, float(std::expm1(std::min(0.5 * double(scale) * double(r) * double(r), 80.0))));
    return B;
}

} // namespace penumbra
