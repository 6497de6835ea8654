#pragma once
#include "render/integrator.h"
#include "render/path_tracer.h"

namespace penumbra {

class PathIntegrator final : public SamplingIntegrator {
public:
    explicit PathIntegrator(const Properties& props);
    void sample(const Scene& scene, Sampler& sampler, const Ray& ray, Color3f* out, RayCounter& rays) const override;
    const PathSettings& settings() const { return settings_; }

private:
    PathSettings settings_;
};

} // namespace penumbra
