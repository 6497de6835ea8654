#pragma once
#include "render/integrator.h"
#include "render/volpath_tracer.h"

namespace penumbra {

// `volpath` (spectral MIS per free-flight segment) and `volpathmis` (spectral MIS over whole paths).
class VolPathIntegrator final : public SamplingIntegrator {
  public:
    VolPathIntegrator(const Properties& props, SpectralMIS spectral);
    void sample(const Scene& scene, Sampler& sampler, const Ray& ray, Color3f* out,
                RayCounter& rays) const override;
    const PathSettings& settings() const { return settings_; }

  private:
    PathSettings settings_;
    SpectralMIS spectral_;
};

} // namespace penumbra
