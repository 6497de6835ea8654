// The bidirectional estimator of warped-area reparameterization in material path space (paper 000 §5.2.2,
// Eq. 54): bidirectional path tracing (render/bdpt*.cpp, its MIS weights and Russian roulette at θ0) whose
// every strategy's contribution C_{s,t} is differentiated as C_{s,t} · f̂(p̄; θ) / f̂(p̄; θ0), with f̂ the
// material-form measurement contribution (diff/path_measurement.h) evaluated at warped vertices: each surface
// vertex p_K carries the field v_K of diff/war/velocity_field.h conditioned on its neighbour toward the
// detector on the connected path p̄ = z_0 … z_{t−1} y_{s−1} … y_0,
//   z_1                  on the camera (primary visibility; the camera factor of war's first vertex);
//   z_k (k ≥ 2)          on z_{k−1};
//   y_j (j < s − 1)      on y_{j+1}: the same for every connection through y_j;
//   y_{s−1} (s ≥ 1)      on z_{t−1}: the connection's light vertex (the light point of s = 1), one warp per
//                        connection.
// A vertex reached along a delta lobe is not warped (no area integral there): it lies where the lobe's
// direction, turning with the geometry, meets its surface (diff/path_measurement.h steered_vertex). The
// tape's derivative of the contribution is then d f̂/dθ + Σ_K ∇·(f̂ v_K) (Eq. 38) per strategy. Eqs. 50–54's
// prefix sums on both subpaths are the tangents of the subpaths' prefix products (diff/path_measurement.h's
// camera_prefix and light_prefix): every shared vertex's warp enters the tape once and every connection
// reuses it, so each connection adds O(1) tape work besides its own light vertex's warp.
//
// Strategies t ≥ 2 (no light tracing), as diff/psdr/bdpt_interior.h. Not covered: infinite lights (clear
// error: use war), delta lights' shadows (not warped, as war), participating media (clear error naming psdr).
#pragma once
#include "diff/war/war.h"

namespace penumbra {

// Throws what war refuses, and scenes with infinite lights.
void require_war_bdpt_support(const Scene& scene, const Parameters& params);

// Forward mode: dI/dθ along params.direction() with per-pixel standard errors over the batches.
DerivativeImage war_bdpt_derivative(const Scene& scene, const Parameters& params, const WarOptions& options);
// Reverse mode: dL/dθ = Σ_pixels adjoint · dI/dθ for every enabled parameter scalar.
Gradient war_bdpt_gradient(const Scene& scene, const Parameters& params, const Image& adjoint,
                           const WarOptions& options);

} // namespace penumbra
