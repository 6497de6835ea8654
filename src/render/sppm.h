#pragma once
#include "render/integrator.h"
#include "render/photon_kernel.h"
#include "render/photon_tracing.h"

namespace penumbra {

// The progressive statistics of one pixel (Hachisuka & Jensen 2009): radius R, accumulated
// (kernel-weighted) photon count N, unnormalized flux τ, and the emission its eye subpaths reached.
struct SPPMPixel {
    float radius = 0.f;
    float count = 0.f;
    Color3f tau{0.f};
    Color3f emission{0.f};
    // The same statistics of the pixel's visible points in media (merged with volume photons in a ball).
    float volume_radius = 0.f, volume_count = 0.f;
    Color3f volume_tau{0.f};
};

// The initial merging radius: `initial_radius`, or 5 × the scene's radius / max(width, height) for 0.
float sppm_radius(const Scene& scene, const SPPMSettings& settings);
// The photon pass of the settings on `threads` threads.
PhotonTracingSettings photon_tracing_settings(const SPPMSettings& settings, int threads);

class SPPMIntegrator final : public Integrator {
  public:
    explicit SPPMIntegrator(const SPPMSettings& settings) : s_(settings) {}
    std::vector<Layer> render(const Scene& scene, const RenderOptions& options,
                              RenderStats& stats) const override;

  private:
    SPPMSettings s_;
};

} // namespace penumbra
