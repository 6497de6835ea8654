#include "diff/volume_motion.h"

#include "diff/material_form.h"
#include "diff/parameters.h"
#include "render/light_medium.h"
#include "scene/scene.h"
#include "scene/tet_mesh.h"

#include <algorithm>
#include <map>
#include <tuple>

namespace penumbra {

namespace {

const std::vector<Motion> no_motions;

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

// The unique edges of a tet mesh as adjacency lists (CSR).
void tet_graph(const TetMesh& mesh, std::vector<uint32_t>& start, std::vector<uint32_t>& neighbors) {
    std::vector<std::pair<uint32_t, uint32_t>> edges;
    for (const auto& t : mesh.tets)
        for (int i = 0; i < 4; ++i)
            for (int j = 0; j < 4; ++j)
                if (i != j) edges.emplace_back(t[i], t[j]);
    std::sort(edges.begin(), edges.end());
    edges.erase(std::unique(edges.begin(), edges.end()), edges.end());
    start.assign(mesh.vertices.size() + 1, 0);
    for (const auto& [a, b] : edges)
        ++start[a + 1];
    for (size_t i = 1; i < start.size(); ++i)
        start[i] += start[i - 1];
    neighbors.clear();
    for (const auto& [a, b] : edges)
        neighbors.push_back(b); // sorted by a: in CSR order
}

} // namespace

// One region where X is not the identity: the interior of a moving shape (its interior medium), or the shell
// between a moving shape and a box around it (the medium around the shape).
struct VolumeRegion {
    const Shape* shape = nullptr;
    const std::vector<Motion>* motions = &no_motions;
    bool vertex_positions = false;
    Vec3f lo, hi; // points outside are not moved by this region
    // Tets (none: the interior of a shape under affine motions only, X given in closed form).
    TetMesh mesh;
    std::unique_ptr<TetLocator> locator;
    std::vector<Vec3f> velocity;   // dX_k/dθ_k at tet vertex i: [i * K + k]
    std::vector<float> divergence; // div dX_k in tet t (the derivative of Eq. (46) at θ0): [t * K + k]
    // vertex_positions: tet vertex i moves by Σ w δx_s over the shape's vertices s ([start[i], start[i+1])).
    std::vector<uint32_t> weight_start;
    std::vector<std::pair<uint32_t, float>> weights;

    size_t K() const { return motions->size(); }

    // Fills velocity (a field evaluated at every vertex, or harmonic away from the fixed ones), the
    // divergences and the vertex_positions weights. The first `fixed_inputs` input vertices are fixed: the
    // shape's (their motion) and the box's corners (zero); the Steiner points on the surface too (the
    // surface's motion there); `shape_vertex[i]`: the shape's vertex at tet vertex i, or -1.
    void interpolate(const std::vector<int64_t>& shape_vertex, size_t fixed_inputs, bool harmonic) {
        const size_t n = mesh.vertices.size(), k_count = K();
        std::vector<bool> fixed(n, false);
        for (size_t i = 0; i < fixed_inputs; ++i)
            fixed[mesh.input_vertex[i]] = true;
        for (const TetMesh::SurfacePoint& s : mesh.surface_points)
            fixed[s.vertex] = true;
        std::vector<uint32_t> start, nb;
        tet_graph(mesh, start, nb);
        velocity.assign(n * k_count, Vec3f(0.f));
        for (size_t i = 0; i < n; ++i)
            for (size_t k = 0; k < k_count; ++k)
                if (shape_vertex[i] >= 0 || (!harmonic && !fixed[i]))
                    velocity[i * k_count + k] = MovedVertices::velocity((*motions)[k], mesh.vertices[i]);
        // Steiner points on the surface move as the surface does there: linearly on its triangle.
        for (const TetMesh::SurfacePoint& s : mesh.surface_points)
            for (size_t k = 0; k < k_count; ++k)
                for (int j = 0; j < 3; ++j)
                    velocity[s.vertex * k_count + k] += velocity[s.triangle[j] * k_count + k] * s.bary[j];
        // Harmonic extension by Gauss-Seidel sweeps of the graph Laplacian (uniform weights): any values at
        // the Steiner points give a continuous X fixed on the boundaries; smooth ones keep J near 1.
        if (harmonic && k_count > 0)
            for (int sweep = 0; sweep < 400; ++sweep) {
                float change = 0.f;
                for (size_t i = 0; i < n; ++i) {
                    if (fixed[i] || start[i] == start[i + 1]) continue;
                    const float inv = 1.f / float(start[i + 1] - start[i]);
                    for (size_t k = 0; k < k_count; ++k) {
                        Vec3f sum(0.f);
                        for (uint32_t e = start[i]; e < start[i + 1]; ++e)
                            sum += velocity[nb[e] * k_count + k];
                        const Vec3f next = sum * inv;
                        change = std::max(change, norm(next - velocity[i * k_count + k]));
                        velocity[i * k_count + k] = next;
                    }
                }
                if (change < 1e-6f) break;
            }
        divergence.assign(mesh.tets.size() * k_count, 0.f);
        for (size_t t = 0; t < mesh.tets.size(); ++t) {
            const auto grad = locator->barycentric_gradients(uint32_t(t));
            for (size_t k = 0; k < k_count; ++k)
                for (int j = 0; j < 4; ++j)
                    divergence[t * k_count + k] += dot(grad[j], velocity[mesh.tets[t][j] * k_count + k]);
        }
        if (vertex_positions) interpolate_weights(shape_vertex, fixed, start, nb, !harmonic);
    }

    // The vertex_positions weights: 1 at the shape's vertices, 0 at the box, and a few Jacobi-style sweeps
    // (the 4 largest weights kept: a few tape nodes per point) at the Steiner points; in the interior they
    // sum to 1 (translating every vertex translates the medium).
    void interpolate_weights(const std::vector<int64_t>& shape_vertex, const std::vector<bool>& fixed,
                             const std::vector<uint32_t>& start, const std::vector<uint32_t>& nb,
                             bool normalize) {
        const size_t n = mesh.vertices.size();
        std::vector<std::vector<std::pair<uint32_t, float>>> w(n);
        for (size_t i = 0; i < n; ++i)
            if (shape_vertex[i] >= 0) w[i] = {{uint32_t(shape_vertex[i]), 1.f}};
        for (const TetMesh::SurfacePoint& s : mesh.surface_points)
            for (int j = 0; j < 3; ++j)
                if (shape_vertex[s.triangle[j]] >= 0)
                    w[s.vertex].emplace_back(uint32_t(shape_vertex[s.triangle[j]]), s.bary[j]);
        for (int sweep = 0; sweep < 8; ++sweep)
            for (size_t i = 0; i < n; ++i) {
                if (fixed[i] || start[i] == start[i + 1]) continue;
                std::map<uint32_t, float> sum;
                for (uint32_t e = start[i]; e < start[i + 1]; ++e)
                    for (const auto& [s, weight] : w[nb[e]])
                        sum[s] += weight;
                std::vector<std::pair<uint32_t, float>> kept(sum.begin(), sum.end());
                std::stable_sort(kept.begin(), kept.end(),
                                 [](const auto& a, const auto& b) { return a.second > b.second; });
                if (kept.size() > 4) kept.resize(4);
                float total = 0.f;
                for (const auto& [s, weight] : kept)
                    total += weight;
                const float scale =
                    normalize ? (total > 0.f ? 1.f / total : 0.f) : 1.f / float(start[i + 1] - start[i]);
                for (auto& [s, weight] : kept)
                    weight *= scale;
                w[i] = std::move(kept);
            }
        weight_start.assign(n + 1, 0);
        weights.clear();
        for (size_t i = 0; i < n; ++i) {
            weights.insert(weights.end(), w[i].begin(), w[i].end());
            weight_start[i + 1] = uint32_t(weights.size());
        }
    }

    // Adds this region's displacement X(p, θ) - p and J - 1 at p (nothing when p lies outside it).
    void add(const Vec3f& p, Vec3<Var>& x, Var* jacobian) const {
        // A little slack: points on the shape's surface at its bounding box, up to rounding.
        const Vec3f slack = (hi - lo) * 1e-4f;
        if (p.x < lo.x - slack.x || p.y < lo.y - slack.y || p.z < lo.z - slack.z || p.x > hi.x + slack.x ||
            p.y > hi.y + slack.y || p.z > hi.z + slack.z)
            return;
        if (!locator) { // affine: the motions' own (first-order) maps, J = det of their linear part
            for (const Motion& m : *motions) {
                const Var theta = Var::parameter(0.f, m.index);
                x += Vec3<Var>(MovedVertices::velocity(m, p)) * theta;
                if (jacobian && m.kind == Parameter::Kind::Scale) *jacobian += theta * 3.f;
            }
            return;
        }
        const auto at = locator->locate(p);
        if (!at) return;
        const auto& tet = mesh.tets[at->tet];
        const size_t k_count = K();
        // Eq. (53): x = Σ_j b_j x_j with x_j = p_j + Σ_k θ_k dX_k(p_j); Eq. (46) to first order: J = 1 + Σ_k
        // θ_k div.
        for (size_t k = 0; k < k_count; ++k) {
            Vec3f v(0.f);
            for (int j = 0; j < 4; ++j)
                v += velocity[tet[j] * k_count + k] * at->bary[j];
            const Var theta = Var::parameter(0.f, (*motions)[k].index);
            x += Vec3<Var>(v) * theta;
            if (jacobian) *jacobian += theta * divergence[at->tet * k_count + k];
        }
        if (!vertex_positions) return;
        const auto grad = locator->barycentric_gradients(at->tet);
        // s -> (weight at p, its gradient), at most 16 terms.
        std::vector<std::pair<uint32_t, std::pair<float, Vec3f>>> terms;
        for (int j = 0; j < 4; ++j)
            for (uint32_t e = weight_start[tet[j]]; e < weight_start[tet[j] + 1]; ++e) {
                const uint32_t s = weights[e].first;
                auto it =
                    std::find_if(terms.begin(), terms.end(), [&](const auto& t) { return t.first == s; });
                if (it == terms.end()) it = terms.insert(terms.end(), {s, {0.f, Vec3f(0.f)}});
                it->second.first += at->bary[j] * weights[e].second;
                it->second.second += grad[j] * weights[e].second;
            }
        const MovedVertices leaves{*shape, no_motions};
        for (const auto& [s, term] : terms) {
            const Vec3<Var> dx = leaves.position(s) - Vec3<Var>(shape->mesh.positions[s]);
            x += dx * Var(term.first);
            if (jacobian) *jacobian += dot(Vec3<Var>(term.second), dx);
        }
    }
};

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
