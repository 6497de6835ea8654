#include "render/aov.h"
#include "render/bdpt.h"
#include "render/direct.h"
#include "render/moment.h"
#include "render/path.h"
#include "render/ptracer.h"
#include "render/sppm.h"
#include "render/volpath.h"
#include "scene/factory.h"

namespace penumbra {

std::shared_ptr<Object> make_integrator(const Properties& props, const LoadContext&) {
    const std::string& type = props.plugin();
    if (type == "path") return std::make_shared<PathIntegrator>(props);
    if (type == "direct") return std::make_shared<DirectIntegrator>(props);
    if (type == "bdpt") return std::make_shared<BidirectionalPathTracer>(props);
    if (type == "ptracer") return std::make_shared<ParticleTracer>(props);
    if (type == "volpath") return std::make_shared<VolPathIntegrator>(props, SpectralMIS::PerSegment);
    if (type == "volpathmis") return std::make_shared<VolPathIntegrator>(props, SpectralMIS::PerPath);
    if (type == "sppm") return std::make_shared<SPPMIntegrator>(props);
    if (type == "aov") return std::make_shared<AOVIntegrator>(props);
    if (type == "moment") return std::make_shared<MomentIntegrator>(props);
    throw_unsupported_plugin(props, ObjectKind::Integrator);
}

} // namespace penumbra
