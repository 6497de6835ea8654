#include "diff/volume_motion.h"

#include "diff/parameters.h"
#include "diff/volume_region.h"
#include "render/light_medium.h"
#include "scene/scene.h"
#include "scene/tet_mesh.h"

#include <algorithm>
#include <map>
#include <tuple>

namespace penumbra {

namespace {

std::string shape_label(const Scene& scene, const Shape& shape) {
    if (!shape.id.empty()) return "shape '" + shape.id + "'";
    for (size_t i = 0; i < scene.shapes.size(); ++i)
        if (scene.shapes[i].get() == &shape) return "shape 'shape_" + std::to_string(i) + "'";
    return "a shape";
}

bool affine(const Motion& m) { return m.kind != Parameter::Kind::Deform; }

// Separating-axis test of a triangle against the box center ± half (Akenine-Möller's 13 axes).
bool triangle_overlaps_box(const Vec3f& a, const Vec3f& b, const Vec3f& c, const Vec3f& center,
                           const Vec3f& half) {
    const Vec3f v[3] = {a - center, b - center, c - center};
    const auto separated = [&](const Vec3f& axis) {
        const float p0 = dot(v[0], axis), p1 = dot(v[1], axis), p2 = dot(v[2], axis);
        const float r = half.x * std::abs(axis.x) + half.y * std::abs(axis.y) + half.z * std::abs(axis.z);
        return std::min({p0, p1, p2}) > r || std::max({p0, p1, p2}) < -r;
    };
    for (int k = 0; k < 3; ++k) {
        Vec3f axis(0.f);
        axis[k] = 1.f;
        if (separated(axis)) return false;
    }
    const Vec3f e[3] = {v[1] - v[0], v[2] - v[1], v[0] - v[2]};
    if (separated(cross(e[0], e[1]))) return false;
    for (int k = 0; k < 3; ++k)
        for (int j = 0; j < 3; ++j) {
            Vec3f axis(0.f);
            axis[k] = 1.f;
            if (separated(cross(axis, e[j]))) return false;
        }
    return true;
}

// Whether every edge of the mesh is shared by exactly two triangles (after welding coincident vertices).
bool closed(const TriangleMesh& mesh) {
    std::map<std::tuple<float, float, float>, uint32_t> welded;
    std::vector<uint32_t> vertex(mesh.positions.size());
    for (size_t i = 0; i < mesh.positions.size(); ++i) {
        const Vec3f& p = mesh.positions[i];
        vertex[i] = welded.try_emplace({p.x, p.y, p.z}, uint32_t(welded.size())).first->second;
    }
    const std::vector<uint32_t>& indices = mesh.indices;
    std::map<std::pair<uint32_t, uint32_t>, int> edges;
    for (size_t t = 0; t + 2 < indices.size(); t += 3)
        for (int k = 0; k < 3; ++k) {
            uint32_t a = vertex[indices[t + k]], b = vertex[indices[t + (k + 1) % 3]];
            if (a == b) continue;
            ++edges[{std::min(a, b), std::max(a, b)}];
        }
    for (const auto& [edge, count] : edges)
        if (count != 2) return false;
    return !edges.empty();
}

} // namespace

struct VolumeMotion::Impl {
    std::map<const Medium*, std::vector<std::unique_ptr<VolumeRegion>>> regions;
    std::vector<std::string> omitted;
};

namespace {

// The medium just outside a shape that declares none: the walk from the sensor to a point beside its first
// triangle (both sides of a shape without media lie in the same medium).
const Medium* medium_around(const Scene& scene, const Shape& shape) {
    if (shape.interior || shape.exterior) return shape.exterior.get();
    const uint32_t* i = &shape.mesh.indices[0];
    const Vec3f c =
        (shape.mesh.positions[i[0]] + shape.mesh.positions[i[1]] + shape.mesh.positions[i[2]]) / 3.f;
    const float scale = std::max(1e-3f, norm(shape.mesh.positions[i[1]] - shape.mesh.positions[i[0]]));
    RayCounter rays;
    return medium_at(scene, c + shape.face_normal(0) * (1e-3f * scale), rays);
}

void bounds(const Shape& shape, Vec3f& lo, Vec3f& hi) {
    lo = Vec3f(Infinity);
    hi = Vec3f(-Infinity);
    for (const Vec3f& p : shape.mesh.positions) {
        lo = min(lo, p);
        hi = max(hi, p);
    }
}

std::vector<int64_t> shape_vertices_of(const TetMesh& mesh, size_t shape_vertex_count) {
    std::vector<int64_t> out(mesh.vertices.size(), -1);
    for (size_t v = shape_vertex_count; v-- > 0;)
        out[mesh.input_vertex[v]] = int64_t(v);
    return out;
}

std::unique_ptr<VolumeRegion> interior_region(const Scene& scene, const Shape& shape,
                                              const Parameters& params) {
    auto r = std::make_unique<VolumeRegion>();
    r->shape = &shape;
    r->motions = &params.motions(&shape);
    r->vertex_positions = shape.vertex_index() >= 0;
    bounds(shape, r->lo, r->hi);
    const std::string name = shape_label(scene, shape);
    // The medium moves with the shape as a whole: a shape inside it would see its boundary move.
    for (const auto& other : scene.shapes) {
        if (other.get() == &shape || other->mesh.positions.empty()) continue;
        Vec3f lo, hi;
        bounds(*other, lo, hi);
        if (lo.x >= r->lo.x && lo.y >= r->lo.y && lo.z >= r->lo.z && hi.x <= r->hi.x && hi.y <= r->hi.y &&
            hi.z <= r->hi.z && medium_around(scene, *other) == shape.interior.get())
            throw Error(
                name + " moves its interior medium, which holds " + shape_label(scene, *other) +
                ": moving a medium's container with shapes inside it is not supported (move the shapes "
                "inside instead)");
    }
    if (!r->vertex_positions && std::all_of(r->motions->begin(), r->motions->end(), affine)) return r;
    if (!closed(shape.mesh))
        throw Error(name + " is not closed: its interior medium cannot be deformed with it");
    // Tets small enough (about 16³ per bounding box) that the interpolated field follows a smooth
    // deformation inside.
    const Vec3f extent = r->hi - r->lo;
    r->mesh = tetrahedralize(shape.mesh.positions, shape.mesh.indices, name,
                             double(extent.x) * extent.y * extent.z / 4096.0);
    r->locator = std::make_unique<TetLocator>(r->mesh);
    r->interpolate(shape_vertices_of(r->mesh, shape.mesh.positions.size()), shape.mesh.positions.size(),
                   false);
    return r;
}

// A box around the shape, as large as twice its bounding box, that meets no other shape's triangles: a face
// of the box stops halfway to a triangle beyond it; a triangle beside the shape on no side (diagonally)
// shrinks every face. Faces closer than a thousandth of the shape's size mean that the shape touches another.
void shell_box(const Scene& scene, const Shape& shape, Vec3f& lo, Vec3f& hi) {
    Vec3f slo, shi;
    bounds(shape, slo, shi);
    const Vec3f extent = shi - slo;
    const float smallest = 1e-3f * norm(extent);
    Vec3f below(0.5f * std::max({extent.x, extent.y, extent.z})), above = below; // the margins
    const Shape* obstacle = nullptr;
    for (int round = 0; round < 64; ++round) {
        lo = slo - below;
        hi = shi + above;
        const Vec3f center = (lo + hi) * 0.5f, half = (hi - lo) * 0.5f;
        bool free = true;
        for (const auto& other : scene.shapes) {
            if (other.get() == &shape) continue;
            const auto& m = other->mesh;
            for (size_t t = 0; t + 2 < m.indices.size(); t += 3) {
                const Vec3f a = m.positions[m.indices[t]], b = m.positions[m.indices[t + 1]],
                            c = m.positions[m.indices[t + 2]];
                if (!triangle_overlaps_box(a, b, c, center, half)) continue;
                free = false;
                obstacle = other.get();
                // The side with the widest gap between the triangle and the shape's bounding box.
                const Vec3f tlo = min(a, min(b, c)), thi = max(a, max(b, c));
                int axis = -1;
                bool upper = false;
                float gap = 0.f;
                for (int k = 0; k < 3; ++k) {
                    if (tlo[k] - shi[k] > gap) gap = tlo[k] - shi[k], axis = k, upper = true;
                    if (slo[k] - thi[k] > gap) gap = slo[k] - thi[k], axis = k, upper = false;
                }
                if (axis < 0) {
                    below *= 0.7f;
                    above *= 0.7f;
                } else {
                    float& margin = upper ? above[axis] : below[axis];
                    margin = std::min(margin, 0.5f * gap);
                }
                break;
            }
            if (!free) break;
        }
        if (free) return;
        if (std::min({below.x, below.y, below.z, above.x, above.y, above.z}) < smallest) break;
    }
    throw Error(
        shape_label(scene, shape) + " touches another shape (" + shape_label(scene, *obstacle) +
        "): no box around it is free of other shapes, so the medium around it cannot be moved with it "
        "(leave a gap between the moving shape and its neighbors)");
}

std::unique_ptr<VolumeRegion> shell_region(const Scene& scene, const Shape& shape, const Parameters& params) {
    auto r = std::make_unique<VolumeRegion>();
    r->shape = &shape;
    r->motions = &params.motions(&shape);
    r->vertex_positions = shape.vertex_index() >= 0;
    shell_box(scene, shape, r->lo, r->hi);
    std::vector<Vec3f> positions = shape.mesh.positions;
    std::vector<uint32_t> indices = shape.mesh.indices;
    const uint32_t base = uint32_t(positions.size());
    for (int c = 0; c < 8; ++c)
        positions.emplace_back(c & 1 ? r->hi.x : r->lo.x, c & 2 ? r->hi.y : r->lo.y,
                               c & 4 ? r->hi.z : r->lo.z);
    // The box's faces (corner c has bit k set when at hi along axis k), two triangles each.
    const uint32_t faces[6][4] = {{0, 2, 6, 4}, {1, 5, 7, 3}, {0, 4, 5, 1},
                                  {2, 3, 7, 6}, {0, 1, 3, 2}, {4, 6, 7, 5}};
    for (const auto& f : faces)
        for (const uint32_t c : {f[0], f[1], f[2], f[0], f[2], f[3]})
            indices.push_back(base + c);
    // A lattice of free points between the shape's bounding box and the box (6 steps across), so that the
    // shell's tets are not long slivers from the surface to the box's corners.
    Vec3f slo, shi;
    bounds(shape, slo, shi);
    const Vec3f step = (r->hi - r->lo) / 6.f;
    for (int z = 1; z < 6; ++z)
        for (int y = 1; y < 6; ++y)
            for (int x = 1; x < 6; ++x) {
                const Vec3f p = r->lo + step * Vec3f(float(x), float(y), float(z));
                const Vec3f gap = max(slo - p, p - shi) / step;
                if (std::max({gap.x, gap.y, gap.z}) > 0.5f) positions.push_back(p);
            }
    r->mesh = tetrahedralize(positions, indices, "the medium around " + shape_label(scene, shape));
    r->locator = std::make_unique<TetLocator>(r->mesh);
    r->interpolate(shape_vertices_of(r->mesh, shape.mesh.positions.size()), base + 8, true);
    return r;
}

} // namespace

VolumeMotion::VolumeMotion(const Scene& scene, const Parameters& params) : impl_(std::make_unique<Impl>()) {
    if (!scene_has_media(scene)) return;
    for (const auto& shape : scene.shapes) {
        if (!params.moves(*shape) || shape->mesh.indices.empty()) continue;
        try {
            const Medium* around = medium_around(scene, *shape);
            // The same medium on both sides: the shell's tets fill the shape too.
            if (shape->interior && shape->interior.get() != around)
                impl_->regions[shape->interior.get()].push_back(interior_region(scene, *shape, params));
            if (around) impl_->regions[around].push_back(shell_region(scene, *shape, params));
        } catch (const Error& e) {
            // Reverse mode enables every vertex_positions: a shape that cannot carry its media is reported,
            // not fatal; a selected motion is.
            if (!params.motions(shape.get()).empty()) throw;
            impl_->omitted.push_back(e.what());
        }
    }
}

VolumeMotion::~VolumeMotion() = default;

bool VolumeMotion::identity() const { return impl_->regions.empty(); }

const std::vector<std::string>& VolumeMotion::omitted() const { return impl_->omitted; }

Vec3<Var> VolumeMotion::position(const Vec3f& p, const Medium* medium, Var* jacobian) const {
    Vec3<Var> x(p);
    if (jacobian) *jacobian = Var(1.f);
    const auto it = impl_->regions.find(medium);
    if (it == impl_->regions.end()) return x;
    // Regions do not overlap on their shapes; where boxes overlap, the first-order motions add.
    for (const auto& region : it->second)
        region->add(p, x, jacobian);
    return x;
}

} // namespace penumbra
