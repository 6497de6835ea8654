#pragma once
#include "render/integrator.h"
#include "render/volpath_tracer.h"

namespace penumbra {

// `volpath` (spectral MIS per free-flight segment) and `volpathmis` (spectral MIS over whole paths).
class VolPathIntegrator final : public SamplingIntegrator {
  public:
    VolPathIntegrator(const PathSettings& settings, SpectralMIS spectral)
        : settings_(settings), spectral_(spectral) {}
    void sample(const Scene& scene, Sampler& sampler, const Ray& ray, Color3f* out,
                RayCounter& rays) const override;

  private:
    PathSettings settings_;
    SpectralMIS spectral_;
};

} // namespace penumbra
