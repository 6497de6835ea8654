#pragma once
#include "render/integrator.h"

namespace penumbra {

class MomentIntegrator final : public SamplingIntegrator {
  public:
    // The `moment` settings: its nested integrators.
    explicit MomentIntegrator(const IntegratorSettings& settings);
    std::vector<std::string> layer_names() const override { return names_; }
    std::vector<std::string> layer_channels() const override { return channels_; }
    void sample(const Scene& scene, Sampler& sampler, const Ray& ray, Color3f* out,
                RayCounter& rays) const override;

  private:
    struct Nested {
        std::shared_ptr<SamplingIntegrator> integrator;
        std::vector<bool> is_main; // per nested layer: its main image (the layer named "")
    };
    std::vector<Nested> nested_;
    std::vector<std::string> names_, channels_;
    size_t first_moments_ = 0; // layers [1, 1 + first_moments_) are first moments; the squares follow
};

} // namespace penumbra
