#pragma once
#include "render/integrator.h"

namespace penumbra {

class AOVIntegrator final : public SamplingIntegrator {
public:
    // The `aov` settings: its AOV list and optional nested integrator.
    explicit AOVIntegrator(const IntegratorSettings& settings);
    std::vector<std::string> layer_names() const override;
    std::vector<std::string> layer_channels() const override;
    void sample(const Scene& scene, Sampler& sampler, const Ray& ray, Color3f* out, RayCounter& rays) const override;

private:
    std::vector<AOV> aovs_;
    std::shared_ptr<SamplingIntegrator> inner_;
};

} // namespace penumbra
