#include "diff/was/implicit_edges.h"

#include "core/error.h"
#include "diff/material_form.h"

#include <embree3/rtcore.h>
#include <tbb/enumerable_thread_specific.h>

#include <algorithm>
#include <cmath>

namespace penumbra {

namespace {

// The interval, along `line`, of the points of triangle t on the plane where the signed distances d vanish:
// its vertices on the plane and its edges' crossings of it, each with its point.
struct Interval {
    float lo = INFINITY, hi = -INFINITY;
    Vec3f plo, phi;
    void add(const Vec3f& p, const Vec3f& line) {
        const float s = dot(p, line);
        if (s < lo) lo = s, plo = p;
        if (s > hi) hi = s, phi = p;
    }
};
Interval plane_crossing(const Triangle3f& t, const float (&d)[3], const Vec3f& line) {
    Interval in;
    for (int k = 0; k < 3; ++k) {
        const int l = (k + 1) % 3;
        if (d[k] == 0.f) in.add(t[k], line);
        if ((d[k] < 0.f && d[l] > 0.f) || (d[k] > 0.f && d[l] < 0.f))
            in.add(t[k] + (t[l] - t[k]) * (d[k] / (d[k] - d[l])), line);
    }
    return in;
}

// Signed distances (times |n|) of t's vertices to the plane through q with normal n; distances below `snap`
// are set to 0, so that a vertex resting on the other triangle's plane counts as on it. False when t lies
// strictly on one side.
bool signed_distances(const Triangle3f& t, const Vec3f& q, const Vec3f& n, float snap, float (&d)[3]) {
    for (int k = 0; k < 3; ++k) {
        d[k] = dot(n, t[k] - q);
        if (std::abs(d[k]) <= snap) d[k] = 0.f;
    }
    return !(d[0] > 0.f && d[1] > 0.f && d[2] > 0.f) && !(d[0] < 0.f && d[1] < 0.f && d[2] < 0.f);
}

bool share_vertex(const Triangle3f& t0, const Triangle3f& t1) {
    for (const Vec3f& p : t0)
        for (const Vec3f& q : t1)
            if (p.x == q.x && p.y == q.y && p.z == q.z) return true;
    return false;
}

Triangle3f triangle(const TriangleMesh& mesh, uint32_t f) {
    const uint32_t* i = &mesh.indices[3 * size_t(f)];
    return {mesh.positions[i[0]], mesh.positions[i[1]], mesh.positions[i[2]]};
}

struct Crossing {
    uint32_t shape0, face0, shape1, face1;
    ImplicitSegment segment;
};

struct CollideContext {
    const std::vector<const TriangleMesh*>* meshes;
    tbb::enumerable_thread_specific<std::vector<Crossing>> found;
};

// Bounds of one triangle for Embree's BVH, padded so that triangles that only touch overlap.
void triangle_bounds(const RTCBoundsFunctionArguments* args) {
    const auto* mesh = static_cast<const TriangleMesh*>(args->geometryUserPtr);
    const Triangle3f t = triangle(*mesh, args->primID);
    Vec3f lo = t[0], hi = t[0];
    for (const Vec3f& p : t) {
        lo = Vec3f(std::min(lo.x, p.x), std::min(lo.y, p.y), std::min(lo.z, p.z));
        hi = Vec3f(std::max(hi.x, p.x), std::max(hi.y, p.y), std::max(hi.z, p.z));
    }
    const float pad = 1e-5f * (std::max({hi.x - lo.x, hi.y - lo.y, hi.z - lo.z}) +
                               std::max({std::abs(lo.x), std::abs(lo.y), std::abs(lo.z)}));
    *args->bounds_o = {lo.x - pad, lo.y - pad, lo.z - pad, 0.f, hi.x + pad, hi.y + pad, hi.z + pad, 0.f};
}

// The narrow phase on the candidate pairs of one BVH leaf pair (called from Embree's worker threads). The
// scene is collided with itself: a pair may be reported in both orders, so only (g0, p0) < (g1, p1) counts.
void collide(void* user, RTCCollision* pairs, unsigned int count) {
    auto* context = static_cast<CollideContext*>(user);
    std::vector<Crossing>& found = context->found.local();
    for (unsigned int k = 0; k < count; ++k) {
        const RTCCollision& c = pairs[k];
        if (c.geomID0 > c.geomID1 || (c.geomID0 == c.geomID1 && c.primID0 >= c.primID1)) continue;
        const Triangle3f t0 = triangle(*(*context->meshes)[c.geomID0], c.primID0),
                         t1 = triangle(*(*context->meshes)[c.geomID1], c.primID1);
        // Triangles with a common corner meet along their shared edge or vertex, a mesh feature.
        if (share_vertex(t0, t1)) continue;
        if (const auto s = triangle_intersection(t0, t1))
            found.push_back({c.geomID0, c.primID0, c.geomID1, c.primID1, *s});
    }
}

} // namespace

std::optional<ImplicitSegment> triangle_intersection(const Triangle3f& t0, const Triangle3f& t1) {
    const Vec3f n0 = cross(t0[1] - t0[0], t0[2] - t0[0]), n1 = cross(t1[1] - t1[0], t1[2] - t1[0]);
    const float len0 = norm(n0), len1 = norm(n1);
    if (len0 == 0.f || len1 == 0.f) return std::nullopt; // degenerate triangle
    // Snap distances below 1e-6 of the pair's extent: a corner resting on the other plane is on it.
    float extent = 0.f;
    for (const Triangle3f* t : {&t0, &t1})
        for (const Vec3f& p : *t)
            extent = std::max(extent, norm(p - t0[0]));
    float d0[3], d1[3];
    if (!signed_distances(t1, t0[0], n0, 1e-6f * extent * len0, d1)) return std::nullopt;
    if (!signed_distances(t0, t1[0], n1, 1e-6f * extent * len1, d0)) return std::nullopt;
    if (d1[0] == 0.f && d1[1] == 0.f && d1[2] == 0.f) return std::nullopt; // coplanar
    const Vec3f line = cross(n0, n1);
    if (norm(line) <= 1e-6f * len0 * len1) return std::nullopt; // parallel planes within the snap
    const Interval i0 = plane_crossing(t0, d0, line), i1 = plane_crossing(t1, d1, line);
    const float lo = std::max(i0.lo, i1.lo), hi = std::min(i0.hi, i1.hi);
    if (!(hi > lo)) return std::nullopt; // disjoint intervals, or a single common point
    return ImplicitSegment{i0.lo > i1.lo ? i0.plo : i1.plo, i0.hi < i1.hi ? i0.phi : i1.phi};
}

ImplicitEdges::ImplicitEdges(const Scene& scene) {
    std::vector<const TriangleMesh*> meshes;
    for (const auto& shape : scene.shapes)
        meshes.push_back(&shape->mesh);
    if (meshes.empty()) return;

    RTCDevice device = rtcNewDevice(nullptr);
    RTCScene bvh = rtcNewScene(device);
    for (size_t g = 0; g < meshes.size(); ++g) {
        RTCGeometry geom = rtcNewGeometry(device, RTC_GEOMETRY_TYPE_USER);
        rtcSetGeometryUserPrimitiveCount(geom, unsigned(meshes[g]->face_count()));
        rtcSetGeometryUserData(geom, const_cast<TriangleMesh*>(meshes[g]));
        rtcSetGeometryBoundsFunction(geom, triangle_bounds, nullptr);
        rtcCommitGeometry(geom);
        rtcAttachGeometryByID(bvh, geom, unsigned(g));
        rtcReleaseGeometry(geom);
    }
    rtcCommitScene(bvh);
    CollideContext context{&meshes, {}};
    rtcCollide(bvh, bvh, collide, &context);
    const RTCError error = rtcGetDeviceError(device);
    rtcReleaseScene(bvh);
    rtcReleaseDevice(device);
    if (error != RTC_ERROR_NONE)
        throw Error("ImplicitEdges: Embree collision failed (error " + std::to_string(int(error)) + ")");

    // Per shape and face, the segments of its crossings (CSR: count, prefix-sum, fill).
    std::vector<ShapeSegments*> per_shape(meshes.size(), nullptr);
    const auto segments_of = [&](uint32_t g) -> ShapeSegments& {
        if (!per_shape[g]) {
            per_shape[g] = &shapes_[scene.shapes[g].get()];
            per_shape[g]->offsets.assign(meshes[g]->face_count() + 1, 0);
        }
        return *per_shape[g];
    };
    for (const std::vector<Crossing>& list : context.found)
        for (const Crossing& c : list) {
            ++segments_of(c.shape0).offsets[c.face0 + 1];
            ++segments_of(c.shape1).offsets[c.face1 + 1];
            ++pairs_;
        }
    std::vector<std::vector<uint32_t>> fill(meshes.size());
    for (size_t g = 0; g < meshes.size(); ++g) {
        if (!per_shape[g]) continue;
        std::vector<uint32_t>& o = per_shape[g]->offsets;
        for (size_t f = 0; f + 1 < o.size(); ++f)
            o[f + 1] += o[f];
        per_shape[g]->segments.resize(o.back());
        fill[g].assign(o.begin(), o.end() - 1);
    }
    for (const std::vector<Crossing>& list : context.found)
        for (const Crossing& c : list) {
            per_shape[c.shape0]->segments[fill[c.shape0][c.face0]++] = {
                c.segment.a, c.segment.b, scene.shapes[c.shape1].get(), c.face1};
            per_shape[c.shape1]->segments[fill[c.shape1][c.face1]++] = {
                c.segment.a, c.segment.b, scene.shapes[c.shape0].get(), c.face0};
        }
}

std::span<const ImplicitSegment> ImplicitEdges::segments(const Shape& shape, uint32_t face) const {
    const auto it = shapes_.find(&shape);
    if (it == shapes_.end()) return {};
    const ShapeSegments& s = it->second;
    return {s.segments.data() + s.offsets[face], s.offsets[face + 1] - s.offsets[face]};
}

NearestSegment ImplicitEdges::nearest(const SurfaceInteraction3f& hit, const Vec3f& origin,
                                      const Vec3f& direction) const {
    NearestSegment best;
    if (!hit.is_valid()) return best;
    const auto across = [&](const Vec3f& v) { return v - direction * dot(v, direction); };
    for (const ImplicitSegment& s : segments(*hit.shape, hit.prim_index)) {
        // q = a + t (b − a) minimizing |P (q − x)|², clamped to the segment.
        const Vec3f pa = across(s.a - origin), pab = across(s.b - s.a);
        const float len2 = dot(pab, pab);
        const float t = len2 > 0.f ? std::clamp(-dot(pa, pab) / len2, 0.f, 1.f) : 0.f;
        const Vec3f q = s.a + (s.b - s.a) * t, to_q = q - origin;
        const float range = norm(to_q);
        if (range == 0.f) continue;
        const float sine = std::min(1.f, norm(across(to_q)) / range);
        if (!best.segment || sine < best.sine) best = {&s, sine, q};
    }
    return best;
}

Vec3<Var> moving_edge_point(const MaterialForm& form, const Shape& shape0, uint32_t face0,
                            const Shape& shape1, uint32_t face1, const Vec3f& c0) {
    // Each moving plane as (n_k, ⟨n_k, p_k⟩) from its triangle's moving corners.
    const auto plane = [&](const Shape& shape, uint32_t face, Vec3<Var>& n) {
        const uint32_t* i = &shape.mesh.indices[3 * size_t(face)];
        const Vec3<Var> p0 = form.position(shape, i[0]);
        n = cross(form.position(shape, i[1]) - p0, form.position(shape, i[2]) - p0);
        return dot(n, p0);
    };
    Vec3<Var> n0, n1;
    const Var r0 = plane(shape0, face0, n0), r1 = plane(shape1, face1, n1);
    const Vec3f t = cross(Vec3f(n0.x.v, n0.y.v, n0.z.v), Vec3f(n1.x.v, n1.y.v, n1.z.v));
    const Vec3<Var> tv(t);
    // c = (r0 (n1 × t) + r1 (t × n0) + ⟨t, c0⟩ (n0 × n1)) / ⟨n0, n1 × t⟩.
    const Vec3<Var> n1t = cross(n1, tv);
    return (n1t * r0 + cross(tv, n0) * r1 + cross(n0, n1) * Var(dot(t, c0))) / dot(n0, n1t);
}

Vec3<Var> edge_following_point(const MaterialForm& form, const SurfaceInteraction3f& hit,
                               const NearestSegment& nearest, const Vec3<Var>& material_point, float factor) {
    if (!nearest.segment) return material_point;
    const Vec3<Var> edge = moving_edge_point(form, *hit.shape, hit.prim_index, *nearest.segment->other,
                                             nearest.segment->other_face, nearest.point);
    const Vec3<Var> p(hit.p);
    return p + (material_point - p) * Var(factor) + (edge - Vec3<Var>(nearest.point)) * Var(1.f - factor);
}

} // namespace penumbra
