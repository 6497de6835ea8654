#pragma once
#include "render/integrator.h"

namespace penumbra {

class DirectIntegrator final : public SamplingIntegrator {
public:
    explicit DirectIntegrator(const Properties& props);
    void sample(const Scene& scene, Sampler& sampler, const Ray& ray, Color3f* out, RayCounter& rays) const override;

private:
    int emitter_samples_ = 1, bsdf_samples_ = 1;
    bool hide_emitters_ = false;
};

} // namespace penumbra
