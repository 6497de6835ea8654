// Spectral data to linear sRGB, the way Mitsuba 3's RGB variants convert `<spectrum>` values:
// integration against the CIE 1931 2-degree color matching functions, then XYZ -> linear sRGB.
#pragma once
#include "core/vector.h"

#include <string>
#include <utility>
#include <vector>

namespace penumbra {

// (wavelength in nm, value) pairs sorted by wavelength. `bounded` clamps to [0,1] (reflectances);
// `illuminant` multiplies by the normalized CIE D65 spectrum, as Mitsuba 3 (>= 3.6) does for non-emission
// spectra so that RGB renders match its spectral modes.
Color3f spectrum_to_rgb(const std::vector<std::pair<float, float>>& samples, bool bounded, bool illuminant);
// Reads a Mitsuba .spd file ("wavelength value" per line, '#' comments); throws Error naming file:line.
std::vector<std::pair<float, float>> read_spd(const std::string& path);
// RGB eta and k of a named conductor ("Cu", "Au", "Ag", "Al", "Cr", ...); returns false for unknown names.
// Values derived from Mitsuba's ior/*.spd data with spectrum_to_rgb (see the table's comment).
bool conductor_ior(const std::string& name, Color3f& eta, Color3f& k);

} // namespace penumbra
