// The interior term of the material-form differential path integral (paper 001 §5.1, Eq. 19 first term),
// estimated by path tracing with NEE in the reference configuration and differentiated with the AD tape:
//   forward mode  dI/dθ along the enabled parameters' direction (a derivative image), and
//   reverse mode  dL/dθ = Σ_pixels ∂L/∂I · dI/dθ for every enabled parameter (a gradient vector).
#pragma once
#include "core/image.h"
#include "diff/bdpt_interior.h"
#include "diff/first_vertex.h"
#include "diff/parameters.h"
#include "diff/pixel_options.h"
#include "diff/sample_cost.h"
#include "render/path_tracer.h"

#include <functional>

namespace penumbra {

struct DiffOptions : PixelOptions {
    bool antithetic = true;    // pixel-level antithetic pairs (paper 001 §5.1, Fig. 6; material-form first vertex)
    FirstVertex first_vertex = FirstVertex::Auto; // diff/first_vertex.h
    InteriorEstimator estimator = InteriorEstimator::Auto; // diff/bdpt_interior.h
};


struct DerivativeImage {
    Image primal;      // the image estimated from the same samples (detached values)
    Image derivative;  // dI/dθ
    Image stderr_img;  // per-pixel standard error of `derivative` (empty with a single batch)
    double seconds = 0;
    SampleCost cost;
};

struct Gradient {
    std::vector<double> values; // dL/dθ, one per enabled parameter scalar
    std::vector<std::string> warnings; // terms the estimate leaves out (shown to the user)
    Image primal;
    double seconds = 0;
    SampleCost cost;
};

// Path settings from the scene's `path`, `volpath` or `bdpt` integrator (defaults otherwise).
PathSettings path_settings(const Scene& scene);

// Throws a clear Error for scenes with participating media (for methods that trace surfaces only).
void require_no_media(const Scene& scene);
DerivativeImage render_derivative(const Scene& scene, const Parameters& params, const DiffOptions& options);
// Throws a clear Error unless `adjoint` has the film's size.
void check_adjoint_size(const Film& film, const Image& adjoint);
// `adjoint` has the film's size: ∂L/∂I per pixel and channel.
Gradient render_gradient(const Scene& scene, const Parameters& params, const Image& adjoint, const DiffOptions& options);

} // namespace penumbra
