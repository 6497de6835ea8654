#pragma once
#include "render/integrator.h"

namespace penumbra {

class ParticleTracer final : public Integrator {
public:
    explicit ParticleTracer(const PathSettings& settings) : settings_(settings) {}
    std::vector<Layer> render(const Scene& scene, const RenderOptions& options, RenderStats& stats) const override;

private:
    // Traces one light path and splats its camera connections into `image`; `media`: the scene has media.
    void trace(const Scene& scene, bool media, Sampler& sampler, Image& image, RayCounter& rays) const;
    PathSettings settings_;
};

} // namespace penumbra
