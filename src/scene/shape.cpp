// Shape: area sampling and surface interactions on a world-space triangle mesh (Mitsuba 3 mesh conventions).
#include "scene/shape.h"

#include "core/warp.h"

#include <sstream>

namespace penumbra {
namespace {

struct Triangle {
    Vec3f p0, p1, p2;
};

Triangle triangle(const TriangleMesh& mesh, uint32_t prim) {
    const uint32_t* i = &mesh.indices[3 * size_t(prim)];
    return {mesh.positions[i[0]], mesh.positions[i[1]], mesh.positions[i[2]]};
}

// Barycentric interpolation b0 a0 + b1 a1 + b2 a2 with b0 = 1 - b1 - b2.
template <typename V> V interpolate(const std::vector<V>& attr, const uint32_t* i, float b1, float b2) {
    return attr[i[0]] * (1.f - b1 - b2) + attr[i[1]] * b1 + attr[i[2]] * b2;
}

} // namespace

void Shape::finalize() {
    const std::string what = "shape '" + plugin + "'" + (id.empty() ? std::string() : " (id '" + id + "')");
    try {
        mesh.validate(what);
    } catch (const Error& e) {
        throw LoadError(location, e.what());
    }
    std::vector<float> areas(mesh.face_count());
    double total = 0.0;
    degenerate_count_ = 0;
    for (uint32_t f = 0; f < areas.size(); ++f) {
        const Triangle t = triangle(mesh, f);
        areas[f] = 0.5f * norm(cross(t.p1 - t.p0, t.p2 - t.p0));
        if (!(areas[f] > 0.f)) {
            areas[f] = 0.f;
            ++degenerate_count_;
        }
        total += areas[f];
    }
    if (!(total > 0.0)) throw LoadError(location, what + ": the mesh has zero surface area");
    area_distribution_ = DiscreteDistribution(areas);
    total_area_ = float(total);
}

Vec3f Shape::face_normal(uint32_t prim) const {
    const Triangle t = triangle(mesh, prim);
    return normalize(cross(t.p1 - t.p0, t.p2 - t.p0));
}

// Triangle chosen with probability area/total (reusing u.x), then a uniform point on it: pdf = 1/total area.
PositionSample3f Shape::sample_position(const Vec2f& u) const {
    float ux = u.x;
    const uint32_t prim = uint32_t(area_distribution_.sample(ux));
    const Vec2f b = warp::square_to_uniform_triangle(Vec2f(ux, u.y));
    const uint32_t* i = &mesh.indices[3 * size_t(prim)];
    PositionSample3f ps;
    ps.p = interpolate(mesh.positions, i, b.x, b.y);
    ps.n = face_normal(prim);
    ps.uv = mesh.uvs.empty() ? b : interpolate(mesh.uvs, i, b.x, b.y);
    ps.pdf = 1.f / total_area_;
    return ps;
}

// Mitsuba 3 mesh interaction: p from barycentrics, n = face normal, shading normal = normalized interpolated
// vertex normal, shading tangent s = Gram-Schmidt of dp/du against it, where dp/du solves
// [p1-p0, p2-p0] = [dp/du, dp/dv] [uv1-uv0, uv2-uv0] (coordinate_system(n) without uvs or when singular).
SurfaceInteraction3f Shape::compute_surface_interaction(const Ray& ray, float t, uint32_t prim, float b1,
                                                        float b2) const {
    const uint32_t* i = &mesh.indices[3 * size_t(prim)];
    const Triangle tri = triangle(mesh, prim);
    const Vec3f dp0 = tri.p1 - tri.p0, dp1 = tri.p2 - tri.p0;

    SurfaceInteraction3f si;
    si.t = t;
    si.p = interpolate(mesh.positions, i, b1, b2);
    si.n = normalize(cross(dp0, dp1));
    si.bary = Vec2f(b1, b2);
    si.shape = this;
    si.prim_index = prim;

    Vec3f dp_du, dp_dv;
    coordinate_system(si.n, dp_du, dp_dv);
    if (mesh.uvs.empty()) {
        si.uv = Vec2f(b1, b2);
    } else {
        si.uv = interpolate(mesh.uvs, i, b1, b2);
        const Vec2f duv0 = mesh.uvs[i[1]] - mesh.uvs[i[0]], duv1 = mesh.uvs[i[2]] - mesh.uvs[i[0]];
        const float det = duv0.x * duv1.y - duv0.y * duv1.x;
        if (det != 0.f) dp_du = (dp0 * duv1.y - dp1 * duv0.y) / det;
    }

    Vec3f ns = si.n;
    if (!face_normals && !mesh.normals.empty()) {
        const Vec3f interpolated = interpolate(mesh.normals, i, b1, b2);
        const float length = norm(interpolated);
        if (length > 0.f && std::isfinite(length)) ns = interpolated / length;
    }
    const Vec3f s = dp_du - ns * dot(ns, dp_du);
    const float s_length = norm(s);
    if (s_length > 0.f && std::isfinite(s_length)) {
        const Vec3f s_unit = s / s_length;
        si.sh_frame = Frame3f(s_unit, cross(ns, s_unit), ns);
    } else {
        si.sh_frame = Frame3f(ns);
    }
    si.wi = si.to_local(-ray.d);
    return si;
}

std::string Shape::to_string() const {
    std::ostringstream os;
    os << "Shape[plugin=" << plugin;
    if (!id.empty()) os << ", id=" << id;
    os << ", triangles=" << mesh.face_count() << ", vertices=" << mesh.vertex_count()
       << ", area=" << total_area_
       << ", normals=" << (face_normals || mesh.normals.empty() ? "face" : "vertex")
       << ", uvs=" << (mesh.uvs.empty() ? "no" : "yes");
    if (degenerate_count_ > 0) os << ", degenerate=" << degenerate_count_;
    if (bsdf) os << ", bsdf=" << bsdf->to_string();
    if (emitter) os << ", emitter=" << emitter->to_string();
    os << "]";
    return os.str();
}

} // namespace penumbra
