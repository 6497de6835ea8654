#include "diff/specular_chains.h"

#include "core/error.h"
#include "core/rng.h"
#include "diff/first_vertex.h"

#include <algorithm>
#include <array>
#include <vector>

namespace penumbra {

namespace {

constexpr int Grid = 128;     // rays per side of the film
constexpr int MaxDelta = 4;   // delta vertices followed per chain
constexpr int MaxProbes = 16; // points on the lights whose visibility an end point records
constexpr uint32_t DeltaLobes = BSDFDeltaReflection | BSDFDeltaTransmission;

bool has_delta_lobe(const SurfaceInteraction3f& hit) {
    const BSDF* bsdf = hit.bsdf();
    return bsdf && bsdf->has(DeltaLobes);
}

// A point on a light (emitter `emitter` sampled at u) whose visibility from the end points is compared.
struct LightProbe {
    const Emitter* emitter;
    Vec2f u;
};

// Where a chain of delta lobes from the camera ends.
struct ChainEnd {
    uint64_t chain = 0;                            // the delta surfaces and lobes on the way
    const Shape* through = nullptr;                // the first of them
    bool chain_moves = false;                      // one of them moves
    const Shape* end = nullptr;                    // the surface it ends on (null: escaped)
    std::array<const Shape*, MaxProbes> blocker{}; // per probe: what hides it (null: seen or not lit)
    uint32_t lit = 0;                              // per probe: the end sees it
};

class ChainGrid {
  public:
    ChainGrid(const Scene& scene, const Parameters& params) : scene_(scene), params_(params) {
        // One point of a point-like light, two of an area light, four directions of an environment.
        const Vec2f u[4] = {Vec2f(0.3f, 0.3f), Vec2f(0.7f, 0.7f), Vec2f(0.3f, 0.7f), Vec2f(0.7f, 0.3f)};
        for (const auto& e : scene.emitters) {
            const int n = e->is_infinite() ? (e->is_delta() ? 1 : 4) : e->shape() ? 2 : 1;
            for (int k = 0; k < n && probes_.size() < size_t(MaxProbes); ++k) probes_.push_back({e.get(), u[k]});
        }
    }

    // The ends of the delta chains of the camera ray through film position s.
    void trace(const Vec2f& s, std::vector<ChainEnd>& out) const {
        out.clear();
        const auto [ray, weight] = scene_.sensor->sample_ray(s, Vec2f(0.5f));
        const SurfaceInteraction3f hit = scene_.intersect(ray);
        if (!hit.is_valid() || !has_delta_lobe(hit)) return;
        ChainEnd start;
        start.through = hit.shape;
        start.chain_moves = !params_.sensor_motions().empty(); // the camera moves every chain
        follow(hit, 0, start, out);
    }

    bool moves(const Shape* shape) const { return shape && params_.moves(*shape); }
    bool moves(const Emitter* emitter) const { return !params_.emitter_motions(emitter).empty(); }
    const std::vector<LightProbe>& probes() const { return probes_; }

  private:
    void follow(const SurfaceInteraction3f& hit, int depth, const ChainEnd& so_far,
                std::vector<ChainEnd>& out) const {
        if (!has_delta_lobe(hit)) return end_at(hit, so_far, out);
        if (depth == MaxDelta) return;
        const BSDFContext ctx{TransportMode::Radiance};
        uint32_t taken = 0;
        for (const float u1 : {0.f, 0.5f, 0.999999f}) {
            const auto [bs, weight] = hit.bsdf()->sample(ctx, hit, u1, Vec2f(0.5f));
            if (is_black(weight) || !(bs.sampled_type & DeltaLobes) || (taken & bs.sampled_type)) continue;
            taken |= bs.sampled_type;
            ChainEnd next = so_far;
            next.chain = mix_bits(so_far.chain ^ (reinterpret_cast<uintptr_t>(hit.shape) + bs.sampled_type));
            next.chain_moves = so_far.chain_moves || moves(hit.shape);
            const SurfaceInteraction3f after = scene_.intersect(hit.spawn_ray(hit.to_world(bs.wo)));
            if (after.is_valid())
                follow(after, depth + 1, next, out);
            else
                out.push_back(next);
        }
    }

    void end_at(const SurfaceInteraction3f& hit, ChainEnd end, std::vector<ChainEnd>& out) const {
        end.end = hit.shape;
        for (size_t k = 0; k < probes_.size(); ++k) {
            const Emitter& e = *probes_[k].emitter;
            const auto [ds, weight] = e.sample_direction(hit, probes_[k].u);
            if (is_black(weight)) continue;
            const SurfaceInteraction3f blocker =
                scene_.intersect(e.is_infinite() ? hit.spawn_ray(ds.d) : hit.spawn_ray_to(ds.p));
            if (blocker.is_valid())
                end.blocker[k] = blocker.shape;
            else
                end.lit |= 1u << k;
        }
        out.push_back(end);
    }

    const Scene& scene_;
    const Parameters& params_;
    std::vector<LightProbe> probes_;
};

// What moves across the boundary between the ends a and b of one chain, or an empty string.
std::string moving_discontinuity(const ChainGrid& grid, const ChainEnd& a, const ChainEnd& b) {
    const auto name = [](const Shape* s) { return s ? "'" + s->id + "'" : std::string("the background"); };
    if (a.end != b.end) {
        if (a.chain_moves || grid.moves(a.end) || grid.moves(b.end))
            return name(a.end) + " meets " + name(b.end);
        return "";
    }
    const uint32_t differ = a.lit ^ b.lit;
    for (size_t k = 0; k < grid.probes().size(); ++k) {
        if (!(differ & (1u << k))) continue;
        const Shape* blocker = a.blocker[k] ? a.blocker[k] : b.blocker[k];
        if (a.chain_moves || grid.moves(a.end) || grid.moves(blocker) || grid.moves(grid.probes()[k].emitter))
            return "the shadow of " + name(blocker) + " on " + name(a.end);
    }
    return "";
}

} // namespace

void require_no_moving_edges_behind_delta_lobes(const Scene& scene, const Parameters& params,
                                                const std::string& method) {
    const bool delta = std::any_of(scene.shapes.begin(), scene.shapes.end(), [](const auto& shape) {
        return shape->bsdf && shape->bsdf->has(DeltaLobes);
    });
    if (!delta || !moves_geometry(scene, params)) return;

    const ChainGrid grid(scene, params);
    const Film& film = *scene.sensor->film;
    const auto position = [&](int i, int j) {
        return Vec2f((float(i) + 0.5f) * float(film.width) / Grid,
                     (float(j) + 0.5f) * float(film.height) / Grid);
    };
    std::vector<std::vector<ChainEnd>> row(Grid), previous(Grid);
    for (int j = 0; j < Grid; ++j) {
        for (int i = 0; i < Grid; ++i)
            grid.trace(position(i, j), row[size_t(i)]);
        for (int i = 0; i < Grid; ++i) {
            const std::vector<ChainEnd>* neighbours[2] = {i > 0 ? &row[size_t(i - 1)] : nullptr,
                                                          j > 0 ? &previous[size_t(i)] : nullptr};
            for (const ChainEnd& a : row[size_t(i)])
                for (const std::vector<ChainEnd>* n : neighbours) {
                    if (!n) continue;
                    for (const ChainEnd& b : *n) {
                        if (b.chain != a.chain) continue;
                        const std::string what = moving_discontinuity(grid, a, b);
                        if (what.empty()) continue;
                        const Vec2f s = position(i, j);
                        throw Error(
                            "method " + method +
                            " cannot differentiate a discontinuity seen only through the "
                            "delta lobes of '" +
                            a.through->id + "' (" + what + ", near pixel (" + std::to_string(int(s.x)) +
                            ", " + std::to_string(int(s.y)) +
                            ")): no boundary term reaches the camera through a mirror or smooth glass yet "
                            "(docs/design.md, \"Delta lobes\")");
                    }
                }
        }
        std::swap(row, previous);
    }
}

} // namespace penumbra
