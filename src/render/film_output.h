// Develops rendered layers into the file the film describes (Mitsuba 3 hdrfilm's pixel and component
// formats).
#pragma once
#include "render/integrator.h"

#include <string>
#include <vector>

namespace penumbra {

// .exr: the main image in the film's pixel format (R,G,B | Y | X,Y,Z, then A), AOV layers as <name>.<letter>,
// stored in the film's component format. .png: the main image only, 8-bit sRGB (gray for luminance formats,
// RGB for xyz ones), with alpha when the film has it. Throws Error on failure.
void write_film(const std::string& path, const Film& film, const std::vector<Layer>& layers);

} // namespace penumbra
