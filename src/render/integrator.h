// Integrators turn a scene into images. Camera-driven ones (path, direct, aov) derive from
// SamplingIntegrator, which owns the parallel, deterministic loop over tiles, pixels and samples.
#pragma once
#include "core/image.h"
#include "core/sampler.h"
#include "render/render.h"
#include "scene/scene.h"

#include <memory>
#include <string>
#include <vector>

namespace penumbra {

// One named output (the main image has an empty name; AOVs are named layers of the EXR). `channels` names the
// EXR channels <name>.<letter>: "RGB" (linear sRGB), "XYZ" (CIE XYZ), or "A" (the film's alpha, in image.x).
struct Layer {
    std::string name;
    Image image;
    std::string channels = "RGB";
};

class Integrator {
public:
    virtual ~Integrator() = default;
    virtual std::vector<Layer> render(const Scene& scene, const RenderOptions& options, RenderStats& stats) const = 0;
};

// Counts rays cast by one worker (merged into RenderStats).
struct RayCounter {
    uint64_t rays = 0;
};

class SamplingIntegrator : public Integrator {
public:
    std::vector<Layer> render(const Scene& scene, const RenderOptions& options, RenderStats& stats) const override;
    // Names of the RGB layers sample() writes, in order.
    virtual std::vector<std::string> layer_names() const { return {""}; }
    // The channel letters of each layer (see Layer::channels), parallel to layer_names().
    virtual std::vector<std::string> layer_channels() const {
        return std::vector<std::string>(layer_names().size(), "RGB");
    }
    // Estimates the layers' values for one camera ray; writes layer_names().size() colors to `out`.
    virtual void sample(const Scene& scene, Sampler& sampler, const Ray& ray, Color3f* out, RayCounter& rays) const = 0;
};

// The integrator of a scene's <integrator> settings (render/integrator_factory.cpp).
std::unique_ptr<Integrator> make_integrator(const IntegratorSettings& settings);
// The same for a camera-driven integrator (camera_driven(settings.plugin)); null for the others.
std::unique_ptr<SamplingIntegrator> make_sampling_integrator(const IntegratorSettings& settings);

} // namespace penumbra
