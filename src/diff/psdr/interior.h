// The interior term of the material-form differential path integral (paper 001 §5.1, Eq. 19 first term),
// estimated by path tracing with NEE in the reference configuration and differentiated with the AD tape:
//   forward mode  dI/dθ along the enabled parameters' direction (a derivative image), and
//   reverse mode  dL/dθ = Σ_pixels ∂L/∂I · dI/dθ for every enabled parameter (a gradient vector).
#pragma once
#include "core/image.h"
#include "diff/first_vertex.h"
#include "diff/parameters.h"
#include "diff/pixel_options.h"
#include "diff/psdr/bdpt_interior.h"
#include "diff/result.h"
#include "render/path_tracer.h"

#include <functional>

namespace penumbra {

struct DiffOptions : PixelOptions {
    bool antithetic = true;    // pixel-level antithetic pairs (paper 001 §5.1, Fig. 6; material-form first vertex)
    FirstVertex first_vertex = FirstVertex::Auto; // diff/first_vertex.h
    InteriorEstimator estimator = InteriorEstimator::Auto; // diff/psdr/bdpt_interior.h
    // The shading horizon's boundary at every vertex (diff/psdr/shading_horizon.h); false only to measure it.
    bool shading_horizon = true;
};


DerivativeImage render_derivative(const Scene& scene, const Parameters& params, const DiffOptions& options);
// `adjoint` has the film's size: ∂L/∂I per pixel and channel.
Gradient render_gradient(const Scene& scene, const Parameters& params, const Image& adjoint, const DiffOptions& options);

} // namespace penumbra
