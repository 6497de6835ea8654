#pragma once
#include "render/integrator.h"

namespace penumbra {

class PathIntegrator final : public SamplingIntegrator {
public:
    explicit PathIntegrator(const Properties& props);
    void sample(const Scene& scene, Sampler& sampler, const Ray& ray, Color3f* out, RayCounter& rays) const override;

private:
    int max_depth_ = -1, rr_depth_ = 5;
    bool hide_emitters_ = false;
};

} // namespace penumbra
