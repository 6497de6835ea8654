#pragma once
#include "render/integrator.h"
#include "render/photon_kernel.h"

namespace penumbra {

// The progressive statistics of one pixel (Hachisuka & Jensen 2009): radius R, accumulated
// (kernel-weighted) photon count N, unnormalized flux τ, and the emission its eye subpaths reached.
struct SPPMPixel {
    float radius = 0.f;
    float count = 0.f;
    Color3f tau{0.f};
    Color3f emission{0.f};
};

class SPPMIntegrator final : public Integrator {
  public:
    explicit SPPMIntegrator(const Properties& props);
    std::vector<Layer> render(const Scene& scene, const RenderOptions& options,
                              RenderStats& stats) const override;

  private:
    int64_t photon_count_ = 250000;
    float initial_radius_ = 0.f;
    float alpha_ = 0.7f;
    int max_depth_ = -1, rr_depth_ = 5;
    int64_t granularity_ = 0, max_passes_ = -1;
    PhotonKernel kernel_ = PhotonKernel::Constant;
};

} // namespace penumbra
