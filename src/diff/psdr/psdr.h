// The total derivative of paper 001 Eq. 19 as separate estimators with their own sample budgets: the interior
// term (diff/psdr/interior.h) plus the boundary terms: primary (camera segments, diff/psdr/primary_boundary.h), direct
// (emitter segments seen by the camera, diff/psdr/direct_boundary.h) and indirect (every other boundary segment,
// diff/psdr/indirect_boundary.h), plus the pixel-boundary term of a box filter (diff/pixel_boundary.h). Each term's
// image is kept for validation against finite differences. In participating media the boundary segments may end
// at medium vertices (shadow sheets; PsdrOptions::volume_boundary).
#pragma once
#include "diff/pixel_boundary.h"
#include "diff/psdr/direct_boundary.h"
#include "diff/psdr/indirect_boundary.h"
#include "diff/psdr/interior.h"
#include "diff/psdr/primary_boundary.h"

#include <array>

namespace penumbra {

struct PsdrOptions {
    DiffOptions interior;     // interior.spp = 0 skips the interior term (its images are zero)
    int primary_spp = 4;      // primary boundary samples per pixel (per batch); 0 disables the term
    int direct_spp = 4;       // direct boundary samples per pixel (per batch); 0 disables the term
    int indirect_spp = 4;     // indirect boundary samples per pixel and technique (per batch); 0 disables it
    int pixel_spp = 4;        // pixel-boundary samples per pixel (per batch; box or cut filters); 0: off
    bool guiding = true;      // contrast-guided sampling of the primary term's edges (always mixed with uniform)
    bool volume_boundary = true; // boundary segments may end at medium vertices (false: surface endpoints only,
                                 // the DTRT-like baseline that misses shadow sheets in media)
    bool calibrated = false;  // the split came from psdr_budget (diff/psdr/budget.h); the description says so
};

// The terms' names, in the order of the derivative's terms.
inline constexpr std::array<const char*, 5> PsdrTermNames = {"interior", "primary", "direct", "indirect", "pixel"};

// The total (interior + boundary) with each term's image, standard error and cost in the order of
// PsdrTermNames; the pixel term only where it applies (needs_pixel_boundary). Standard errors combine the
// terms' (independent).
DerivativeImage psdr_derivative(const Scene& scene, const Parameters& params, const PsdrOptions& options);
Gradient psdr_gradient(const Scene& scene, const Parameters& params, const Image& adjoint, const PsdrOptions& options);

} // namespace penumbra
