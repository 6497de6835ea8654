// The per-pixel sample loops of the estimators that integrate the image derivative over camera samples (the
// interior term of diff/psdr/interior.h; war, war-bdpt and was): forward mode in independent batches with
// per-pixel standard errors, reverse mode's adjoint pass dL/dθ = Σ_pixels ∂L/∂I · dI/dθ, the flux across the
// film's edges that a warped estimator adds per batch (diff/pixel_boundary.h), and the warning for the
// shadows of delta lights that a warp does not see. An estimator supplies its per-sample function only.
// Random numbers depend on (seed, pixel, sample) alone: neither tiles nor threads change a result.
#pragma once
#include "diff/pixel_boundary.h"
#include "diff/pixel_options.h"
#include "diff/result.h"

#include <chrono>
#include <memory>
#include <string>

namespace penumbra {

// Sample m of pixel (x, y) in a pass with the given seed (pixel = y · width + x).
struct PixelSample {
    int x, y;
    uint64_t pixel;
    int m;
    uint64_t seed;
};

// The camera samples of one tile: one object per tile, which may keep state across the tile's pixels.
class TileSamples {
  public:
    virtual ~TileSamples() = default;
    // One camera sample's contribution as a tape value, `sampler` started for it; `rays` counts rays.
    virtual Color3<Var> sample(Sampler& sampler, const PixelSample& s, RayCounter& rays) = 0;
    // Forward mode only: around each pixel's samples, and after each finite sample's tangents are known, a
    // correction of its derivative (a control variate).
    virtual void begin_pixel(int, int) {}
    virtual void correct(const std::vector<float>&, Vec3d&) {}
    virtual void end_pixel() {}
};

// The tangent of a tape value after Tape::forward (0 for a constant).
inline float tangent_of(const Var& v, const std::vector<float>& tangent) {
    return v.id < 0 ? 0.f : tangent[v.id];
}

using SampleFunction = std::function<Color3<Var>(Sampler&, const PixelSample&, RayCounter&)>;
using TileSamplesFactory = std::function<std::unique_ptr<TileSamples>()>;

// Tiles whose samples are `f`'s, with no state of their own.
TileSamplesFactory per_sample(SampleFunction f);

// One estimator's pass over the film: its options, its tiles' samples and what it adds.
struct PixelLoop {
    PixelLoop(const Scene& s, const Parameters& p, const PixelOptions& o) : scene(s), params(p), options(o) {}
    const Scene& scene;
    const Parameters& params;
    PixelOptions options;    // batches: forward mode only; path: the film-edge term's
    bool antithetic = false; // samples 2k and 2k + 1 share the sampler's stream k (the estimator mirrors one)
    TileSamplesFactory tiles;
    // The flux across the edges where the filters jump for a batch seed (unset: none).
    std::function<PixelBoundary(uint64_t seed)> film_edge;
    // The method named by the warning that point and spot lights' shadows do not move (empty: no warning).
    std::string unwarped_delta_lights;
    // The results' one-line description, and the name of the one term of the derivative.
    std::string description, term;
    // The results' `seconds` count from the loop's making (the estimator's set-up included).
    std::chrono::steady_clock::time_point start = std::chrono::steady_clock::now();
};

// Throws a clear Error unless a parameter is enabled and the scene has a sensor with a film.
void require_film(const Scene& scene, const Parameters& params);
// Throws a clear Error unless `adjoint` has the film's size.
void check_adjoint_size(const Film& film, const Image& adjoint);
// Throws a clear Error for scenes with participating media (for methods that trace surfaces only).
void require_no_media(const Scene& scene);

// Forward mode: dI/dθ along params.direction(), with per-pixel standard errors over the batches.
DerivativeImage pixel_derivative(const PixelLoop& loop);
// Reverse mode with one batch: dL/dθ for every enabled parameter scalar given the adjoint ∂L/∂I.
Gradient pixel_gradient(const PixelLoop& loop, const Image& adjoint);

// Whether the filter jumps at its support's edge (a box; tent and gaussian fall to zero there): the pixel
// edges are then static discontinuities of every pixel (diff/pixel_boundary.h).
bool filter_jumps(const ReconstructionFilter& filter);
// The film-edge term's samples per unit edge segment: about `spp` per pixel whose filter jumps at its own
// edges (~2 unit segments per pixel), `spp` per unit of the film's edge otherwise.
int film_edge_strata(const Film& film, int spp);

} // namespace penumbra
