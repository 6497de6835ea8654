// The surface interaction at a material point (triangle prim, barycentrics b1, b2) of a mesh, templated on the
// scalar type and on where vertex data comes from: the mesh itself when rendering, or the moving geometry
// X(p, θ) of the differentiable estimators (paper 001 §4.1). One code path for both.
#pragma once
#include "scene/shape.h"

#include <type_traits>

namespace penumbra {

// Vertex data of the mesh as stored (the reference configuration).
struct MeshVertices {
    const TriangleMesh& mesh;
    Vec3f position(uint32_t v) const { return mesh.positions[v]; }
    Vec3f normal(uint32_t v) const { return mesh.normals[v]; }
};

// The geometric normal and dp/du of triangle i, which solves [p1-p0, p2-p0] = [dp/du, dp/dv] [uv1-uv0, uv2-uv0]
// (coordinate_system(n) without uvs or when singular).
template <typename T>
void triangle_normal_and_dp_du(const TriangleMesh& mesh, const uint32_t* i, const Vec3<T>& dp0, const Vec3<T>& dp1,
                               Vec3<T>& n, Vec3<T>& dp_du) {
    n = normalize(cross(dp0, dp1));
    Vec3<T> dp_dv;
    coordinate_system(n, dp_du, dp_dv);
    if (mesh.uvs.empty()) return;
    const Vec2f duv0 = mesh.uvs[i[1]] - mesh.uvs[i[0]], duv1 = mesh.uvs[i[2]] - mesh.uvs[i[0]];
    const float det = duv0.x * duv1.y - duv0.y * duv1.x;
    if (det != 0.f) dp_du = (dp0 * T(duv1.y) - dp1 * T(duv0.y)) / T(det);
}

// Mitsuba 3 mesh interaction: p from barycentrics, n = face normal, shading normal = normalized interpolated
// vertex normal, shading tangent s = Gram-Schmidt of dp/du against it, where dp/du solves
// [p1-p0, p2-p0] = [dp/du, dp/dv] [uv1-uv0, uv2-uv0] (coordinate_system(n) without uvs or when singular).
// `t` and `wi` are left for the caller (they depend on the ray or the neighbouring path vertex). The
// barycentrics are in T too: a fixed material point has constant ones; the point where a fixed ray meets a
// moving triangle has barycentrics that depend on θ (diff/material_form.h).
template <typename T, typename Vertices>
SurfaceInteraction<T> surface_interaction(const Shape& shape, uint32_t prim, const Vec2<T>& bary, const Vertices& vertices) {
    using std::sqrt;
    const TriangleMesh& mesh = shape.mesh;
    const uint32_t* i = &mesh.indices[3 * size_t(prim)];
    const Vec3<T> p0 = vertices.position(i[0]), p1 = vertices.position(i[1]), p2 = vertices.position(i[2]);
    const T b1 = bary.x, b2 = bary.y, b0 = T(1.f) - b1 - b2;
    const Vec3<T> dp0 = p1 - p0, dp1 = p2 - p0;

    SurfaceInteraction<T> si;
    si.p = p0 * b0 + p1 * b1 + p2 * b2;
    si.bary = Vec2f(detach(b1), detach(b2));
    si.shape = &shape;
    si.prim_index = prim;
    si.uv = mesh.uvs.empty() ? Vec2<T>(b1, b2)
                             : Vec2<T>(mesh.uvs[i[0]]) * b0 + Vec2<T>(mesh.uvs[i[1]]) * b1 +
                                   Vec2<T>(mesh.uvs[i[2]]) * b2;
    Vec3<T> dp_du;
    if constexpr (std::is_same_v<T, float> && std::is_same_v<Vertices, MeshVertices>) {
        // The stored mesh: what depends on the triangle alone was computed once by finalize() (below).
        if (const TriangleShading* cached = shape.triangle_shading(prim)) {
            si.n = cached->n;
            if (cached->constant_frame()) {
                si.sh_frame = cached->frame;
                return si;
            }
            dp_du = cached->frame.s;
        } else {
            triangle_normal_and_dp_du(mesh, i, dp0, dp1, si.n, dp_du);
        }
    } else {
        triangle_normal_and_dp_du(mesh, i, dp0, dp1, si.n, dp_du);
    }

    Vec3<T> ns = si.n;
    if (!shape.face_normals && !mesh.normals.empty()) {
        const Vec3<T> interpolated =
            vertices.normal(i[0]) * b0 + vertices.normal(i[1]) * b1 + vertices.normal(i[2]) * b2;
        const T length = norm(interpolated);
        if (length > T(0) && std::isfinite(detach(length))) ns = interpolated / length;
    }
    const Vec3<T> s = dp_du - ns * dot(ns, dp_du);
    const T s_length = norm(s);
    if (s_length > T(0) && std::isfinite(detach(s_length))) {
        const Vec3<T> s_unit = s / s_length;
        si.sh_frame = Frame<T>(s_unit, cross(ns, s_unit), ns);
    } else {
        si.sh_frame = Frame<T>(ns);
    }
    return si;
}

} // namespace penumbra
