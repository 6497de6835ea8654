// Shape: area sampling and surface interactions on a world-space triangle mesh (Mitsuba 3 mesh conventions).
#include "scene/shape.h"

#include "scene/shape_interaction.h"

#include "core/warp.h"

#include <limits>
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
    build_rings();
    build_triangle_shading();
}

// The per-hit work that depends on the triangle alone (normal, dp/du, and the whole shading frame when it
// is constant over the triangle) done once per triangle by surface_interaction() itself. With three equal
// vertex normals the frame is the one at vertex 0 (elsewhere the interpolation rounds to within an ulp of it).
void Shape::build_triangle_shading() {
    triangles_.clear();
    std::vector<TriangleShading> triangles(mesh.face_count());
    const bool flat = flat_shading();
    for (uint32_t f = 0; f < triangles.size(); ++f) {
        const uint32_t* i = &mesh.indices[3 * size_t(f)];
        TriangleShading& c = triangles[f];
        if (flat || (mesh.normals[i[0]] == mesh.normals[i[1]] && mesh.normals[i[0]] == mesh.normals[i[2]])) {
            const SurfaceInteraction3f si = surface_interaction<float>(*this, f, Vec2f(0.f), MeshVertices{mesh});
            c.n = si.n;
            c.frame = si.sh_frame;
        } else {
            triangle_normal_and_dp_du(mesh, i, mesh.positions[i[1]] - mesh.positions[i[0]],
                                      mesh.positions[i[2]] - mesh.positions[i[0]], c.n, c.frame.s);
            c.frame.n = Vec3f(std::numeric_limits<float>::quiet_NaN());
        }
    }
    triangles_ = std::move(triangles);
}

// Counting sort of the faces by vertex.
void Shape::build_rings() {
    ring_offsets_.clear();
    ring_faces_.clear();
    if (face_normals || mesh.normals.empty()) return;
    ring_offsets_.assign(mesh.vertex_count() + 1, 0);
    for (const uint32_t v : mesh.indices) ++ring_offsets_[v + 1];
    for (size_t v = 0; v < mesh.vertex_count(); ++v) ring_offsets_[v + 1] += ring_offsets_[v];
    ring_faces_.resize(mesh.indices.size());
    std::vector<uint32_t> next(ring_offsets_.begin(), ring_offsets_.end() - 1);
    for (size_t i = 0; i < mesh.indices.size(); ++i) ring_faces_[next[mesh.indices[i]]++] = uint32_t(i / 3);
}

void Shape::update_from_group() {
    mesh.positions = group_shape->mesh.positions;
    mesh.normals = group_shape->mesh.normals;
    mesh.apply_transform(instance_to_world);
}

Vec3f Shape::face_normal(uint32_t prim) const {
    if (!triangles_.empty()) return triangles_[prim].n;
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
    ps.prim = prim;
    ps.bary = b;
    return ps;
}

SurfaceInteraction3f Shape::compute_surface_interaction(const Ray& ray, float t, uint32_t prim, float b1,
                                                        float b2) const {
    SurfaceInteraction3f si = surface_interaction<float>(*this, prim, Vec2f(b1, b2), MeshVertices{mesh});
    si.t = t;
    si.wi = si.to_local(-ray.d);
    return si;
}

// Curves keep their tessellation's vertices out of the parameters (Mitsuba's key is `control_points`, which
// penumbra does not expose); their motions (translate, rotate, scale) are differentiated like any shape's.
void Shape::traverse(ParamVisitor& v) {
    const bool curve = plugin == "linearcurve" || plugin == "bsplinecurve";
    if (!mesh.positions.empty() && !curve && !group_shape)
        v.put_array("vertex_positions", &mesh.positions[0].x, {int(mesh.vertex_count()), 3},
                    &vertex_param_index, true);
    if (bsdf) v.put_object("bsdf", bsdf.get());
    if (emitter) v.put_object("emitter", emitter.get());
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
