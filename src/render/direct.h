#pragma once
#include "render/integrator.h"

namespace penumbra {

class DirectIntegrator final : public SamplingIntegrator {
public:
    explicit DirectIntegrator(const DirectSettings& settings) : settings_(settings) {}
    void sample(const Scene& scene, Sampler& sampler, const Ray& ray, Color3f* out, RayCounter& rays) const override;

private:
    DirectSettings settings_;
};

} // namespace penumbra
