// Round curves (Mitsuba 3's linearcurve and bsplinecurve) as triangle meshes: the curve file format, and
// the tube swept by a sphere of varying radius along a centerline, tessellated ring by ring.
#pragma once
#include "scene/factory.h"
#include "scene/mesh.h"

#include <vector>

namespace penumbra {

struct ControlPoint {
    Vec3f p;      // world space (to_world applied)
    float radius; // not transformed, as in Mitsuba
};

// Reads the curve file of `props` ("x y z radius" per line, blank lines between curves), applies to_world to
// the positions; every curve must have at least `min_points`. Errors name the file and line.
std::vector<std::vector<ControlPoint>> load_curves(const Properties& props, const LoadContext& ctx,
                                                   size_t min_points);

constexpr int CurveRingSegments = 32; // vertices around a ring

// Appends a ring around the centerline point c with tangent dc (d c / d t) and radius r with derivative dr:
// the circle where the swept sphere touches its envelope, c + r n with the envelope normal
// n = cos(a) radial + sin(a) t, sin(a) = -dr / |dc| (Mitsuba's normal (|c'|^2 rad - r r' c')). u runs around
// the ring from Mitsuba's u_rad toward u_rot (guide +z), v is given. Returns the first vertex index.
uint32_t append_ring(TriangleMesh& m, const Vec3f& c, const Vec3f& dc, float r, float dr, float v);
// Two rings of append_ring joined by quads (outward normals).
void connect_rings(TriangleMesh& m, uint32_t ring0, uint32_t ring1);
// A sphere (a joint or an end cap) with poles along `axis`, u around it in the frame of `axis`, uv.y = v.
void append_sphere(TriangleMesh& m, const Vec3f& c, float r, const Vec3f& axis, float v);

} // namespace penumbra
