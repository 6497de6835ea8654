// Curve files and the tessellation of round curves (see curve_tube.h).
#include "scene/shapes/curve_tube.h"

#include <cmath>
#include <fstream>
#include <sstream>

namespace penumbra {
namespace {

constexpr int SphereRings = 16;

// Mitsuba's local_frame: u_rot = the guide +z made orthogonal to the tangent t (+y when t is along z),
// u_rad = u_rot x t.
std::pair<Vec3f, Vec3f> local_frame(const Vec3f& t) {
    const Vec3f guide(0.f, 0.f, 1.f);
    const Vec3f g = guide - t * dot(t, guide);
    const Vec3f u_rot = norm(g) > 1e-6f ? g / norm(g) : Vec3f(0.f, 1.f, 0.f);
    return {u_rot, cross(u_rot, t)};
}

} // namespace

std::vector<std::vector<ControlPoint>> load_curves(const Properties& props, const LoadContext& ctx,
                                                   size_t min_points) {
    const std::string name = props.get_string("filename");
    const std::string path = ctx.resolve(name, props.location("filename"));
    const Transform to_world = props.get_transform("to_world");
    std::ifstream in(path);
    if (!in) props.raise("filename", "cannot read curve file '" + name + "'");
    std::vector<std::vector<ControlPoint>> curves;
    bool new_curve = true;
    int first_line = 0; // of the last curve
    auto check_last = [&] {
        if (!curves.empty() && curves.back().size() < min_points)
            props.raise("filename", name + ":" + std::to_string(first_line) + ": a " + props.plugin() +
                                        " needs at least " + std::to_string(min_points) +
                                        " control points per curve, the one starting here has " +
                                        std::to_string(curves.back().size()));
    };
    std::string text;
    int line = 0;
    while (std::getline(in, text)) {
        ++line;
        std::istringstream fields(text);
        ControlPoint cp;
        std::string rest;
        if (text.find_first_not_of(" \t\r") == std::string::npos) {
            new_curve = true;
            continue;
        }
        if (!(fields >> cp.p.x >> cp.p.y >> cp.p.z >> cp.radius) || (fields >> rest) || !is_finite(cp.p) ||
            !std::isfinite(cp.radius) || cp.radius < 0.f)
            props.raise("filename", name + ":" + std::to_string(line) +
                                        ": expected a control point 'x y z radius' (finite, radius >= 0)");
        if (new_curve) {
            check_last();
            curves.emplace_back();
            first_line = line;
            new_curve = false;
        }
        cp.p = to_world.apply_point(cp.p);
        curves.back().push_back(cp);
    }
    if (curves.empty()) props.raise("filename", name + ": no control points");
    check_last();
    return curves;
}

uint32_t append_ring(TriangleMesh& m, const Vec3f& c, const Vec3f& dc, float r, float dr, float v) {
    const float speed = norm(dc);
    const Vec3f t = dc / speed;
    const auto [u_rot, u_rad] = local_frame(t);
    const float sin_a = std::clamp(-dr / speed, -1.f, 1.f), cos_a = std::sqrt(1.f - sin_a * sin_a);
    const uint32_t first = uint32_t(m.positions.size());
    for (int k = 0; k <= CurveRingSegments; ++k) {
        // The seam vertex (u = 1) repeats the first one exactly, so that the seam's edges are merged as
        // interior edges (cos(2 pi) and sin(2 pi) are not exactly 1 and 0 in float).
        const float u = float(k) / float(CurveRingSegments),
                    phi = k == CurveRingSegments ? 0.f : 2.f * Pi * u;
        const Vec3f n = (u_rad * std::cos(phi) + u_rot * std::sin(phi)) * cos_a + t * sin_a;
        m.positions.push_back(c + n * r);
        m.normals.push_back(n);
        m.uvs.emplace_back(u, v);
    }
    return first;
}

// Quads between ring0 (behind) and ring1 (ahead along the tangent): around the ring u turns from u_rad to
// u_rot = t x u_rad, so (step in u) x (step along t) points outward. Triangles with two coincident vertices
// (at a ring of radius zero: a sphere's pole, a curve tapering to a point) are left out.
void connect_rings(TriangleMesh& m, uint32_t ring0, uint32_t ring1) {
    auto add = [&](uint32_t a, uint32_t b, uint32_t c) {
        const Vec3f& pa = m.positions[a];
        const Vec3f& pb = m.positions[b];
        const Vec3f& pc = m.positions[c];
        if (pa == pb || pb == pc || pc == pa) return;
        m.indices.insert(m.indices.end(), {a, b, c});
    };
    for (uint32_t k = 0; k < uint32_t(CurveRingSegments); ++k) {
        add(ring0 + k, ring0 + k + 1, ring1 + k + 1);
        add(ring0 + k, ring1 + k + 1, ring1 + k);
    }
}

// Rings of latitude from the -axis pole to the +axis pole, each a ring of append_ring with the sphere's
// radius and no axial offset (the poles are rings of radius zero).
void append_sphere(TriangleMesh& m, const Vec3f& c, float r, const Vec3f& axis, float v) {
    uint32_t previous = 0;
    for (int i = 0; i <= SphereRings; ++i) {
        const float theta = Pi * float(i) / float(SphereRings);                    // from -axis to +axis
        const float z = i == 0 ? -1.f : i == SphereRings ? 1.f : -std::cos(theta); // exact poles
        // The ring at height r z, of radius r sqrt(1 - z^2): append_ring's ring with sin(a) = z.
        const uint32_t ring = append_ring(m, c, axis, r, -z * norm(axis), v);
        if (i > 0) connect_rings(m, previous, ring);
        previous = ring;
    }
}

} // namespace penumbra
