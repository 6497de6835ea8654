#include "render/aov.h"
#include "render/bdpt.h"
#include "render/direct.h"
#include "render/moment.h"
#include "render/path.h"
#include "render/ptracer.h"
#include "render/sppm.h"
#include "render/volpath.h"

namespace penumbra {

std::unique_ptr<SamplingIntegrator> make_sampling_integrator(const IntegratorSettings& settings) {
    const std::string& type = settings.plugin;
    if (type == "path") return std::make_unique<PathIntegrator>(settings.path);
    if (type == "direct") return std::make_unique<DirectIntegrator>(settings.direct);
    if (type == "volpath") return std::make_unique<VolPathIntegrator>(settings.path, SpectralMIS::PerSegment);
    if (type == "volpathmis") return std::make_unique<VolPathIntegrator>(settings.path, SpectralMIS::PerPath);
    if (type == "aov") return std::make_unique<AOVIntegrator>(settings);
    if (type == "moment") return std::make_unique<MomentIntegrator>(settings);
    return nullptr;
}

std::unique_ptr<Integrator> make_integrator(const IntegratorSettings& settings) {
    if (std::unique_ptr<SamplingIntegrator> sampling = make_sampling_integrator(settings)) return sampling;
    const std::string& type = settings.plugin;
    if (type == "bdpt") return std::make_unique<BidirectionalPathTracer>(settings.bdpt);
    if (type == "ptracer") return std::make_unique<ParticleTracer>(settings.path);
    if (type == "sppm") return std::make_unique<SPPMIntegrator>(settings.sppm);
    throw Error("internal error: no integrator for the settings of '" + type + "'");
}

} // namespace penumbra
