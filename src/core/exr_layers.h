// Multi-layer OpenEXR output (AOVs): the layer named "" becomes R,G,B; others become <name>.R/G/B.
#pragma once
#include "core/image.h"

#include <string>
#include <utility>
#include <vector>

namespace penumbra {

// All images must have the same size. Written to a temporary file and renamed; throws Error on failure.
void write_exr_layers(const std::string& path, const std::vector<std::pair<std::string, const Image*>>& layers);

} // namespace penumbra
