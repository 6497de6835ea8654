#include "diff/volume_region.h"

#include "diff/material_form.h"

#include <algorithm>
#include <map>

namespace penumbra {

namespace {

const std::vector<Motion> no_motions;

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

void VolumeRegion::interpolate(const std::vector<int64_t>& shape_vertex, size_t fixed_inputs, bool harmonic) {
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

void VolumeRegion::interpolate_weights(const std::vector<int64_t>& shape_vertex,
                                       const std::vector<bool>& fixed, const std::vector<uint32_t>& start,
                                       const std::vector<uint32_t>& nb, bool normalize) {
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

void VolumeRegion::add(const Vec3f& p, Vec3<Var>& x, Var* jacobian) const {
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
            auto it = std::find_if(terms.begin(), terms.end(), [&](const auto& t) { return t.first == s; });
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

} // namespace penumbra
