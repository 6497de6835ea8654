#pragma once
#include "render/integrator.h"
#include "render/path_tracer.h"

namespace penumbra {

class PathIntegrator final : public SamplingIntegrator {
public:
    explicit PathIntegrator(const PathSettings& settings) : settings_(settings) {}
    void sample(const Scene& scene, Sampler& sampler, const Ray& ray, Color3f* out, RayCounter& rays) const override;

private:
    PathSettings settings_;
};

} // namespace penumbra
