#include "render/render.h"

#include "render/integrator.h"
#include "render/path.h"

namespace penumbra {

std::vector<Layer> render_layers(const Scene& scene, const RenderOptions& options, RenderStats* stats) {
    if (!scene.sensor || !scene.sensor->film || !scene.sensor->sampler) throw Error("render: the scene has no sensor");
    if (options.spp < 0) throw Error("render: the sample count must be positive");
    RenderStats local;
    RenderStats& s = stats ? *stats : local;
    if (scene.integrator) return make_integrator(*scene.integrator)->render(scene, options, s);
    return PathIntegrator(PathSettings{}).render(scene, options, s);
}

Image render(const Scene& scene, const RenderOptions& options, RenderStats* stats) {
    return std::move(render_layers(scene, options, stats).front().image);
}

} // namespace penumbra
