#pragma once
#include "render/integrator.h"

namespace penumbra {

class AOVIntegrator final : public SamplingIntegrator {
public:
    enum class Type { Depth, Position, UV, GeoNormal, ShNormal, Albedo, PrimIndex, ShapeIndex };
    explicit AOVIntegrator(const Properties& props);
    std::vector<std::string> layer_names() const override;
    std::vector<std::string> layer_channels() const override;
    void sample(const Scene& scene, Sampler& sampler, const Ray& ray, Color3f* out, RayCounter& rays) const override;

private:
    struct AOV {
        std::string name;
        Type type;
    };
    std::vector<AOV> aovs_;
    std::shared_ptr<SamplingIntegrator> inner_;
};

} // namespace penumbra
