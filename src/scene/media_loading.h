// Pieces shared by the medium and volume factories (scene/media.cpp, scene/volumes/*.cpp).
#pragma once
#include "scene/factory.h"
#include "scene/medium.h"

namespace penumbra {

// A volume parameter: a nested <volume>, or a float/spectrum (a constvolume); `def` when absent.
std::shared_ptr<Volume> get_volume(const Properties& props, const std::string& name, const Color3f& def);
// The medium's nested phase function (isotropic when absent; more than one is an error).
std::shared_ptr<PhaseFunction> get_phase(const Properties& props, const LoadContext& ctx);

std::shared_ptr<Object> make_heterogeneous_medium(const Properties& props, const LoadContext& ctx);
std::shared_ptr<Object> make_gridvolume(const Properties& props, const LoadContext& ctx);

} // namespace penumbra
