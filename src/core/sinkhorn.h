// Entropic optimal transport between two weighted point clouds in 5-D (RGB + screen xy): the approximate
// optimal transport [Cuturi 2013; Feydy et al. 2019] behind the pixel and path-to-pixel matching of Xing et
// al. [2022, 2023] that paper 003 (§3.2, §5.3) uses for its DPM-G loss.
//
// Cost C(x, y) = ½ (‖Δrgb‖² + w ‖Δxy‖²) (GeomLoss's p = 2 cost, with a weight w on the position part);
// regularization ε = blur². The dual potentials f, g of the source and target are found by log-domain
// Sinkhorn iterations, with ε annealed from the squared diameter of the clouds down to blur² by the factor
// scaling² per step (GeomLoss's ε-scaling). The cost matrix is never stored: every pass computes its rows on
// the fly, in parallel over rows, each row in a fixed order, so the result does not depend on the thread
// count.
#pragma once
#include <Eigen/Core>

namespace penumbra {

// One point per row: (r, g, b, x, y).
using Points5 = Eigen::Matrix<double, Eigen::Dynamic, 5>;

struct SinkhornOptions {
    double blur = 0.01;           // final ε = blur² (GeomLoss's default for the paper's matching)
    double scaling = 0.9;         // blur ratio per annealing step, in [0, 1); 0 runs at the final ε only
    double position_weight = 1.0; // w of the xy part of the cost relative to the colour part
    double tolerance = 1e-3;      // stop when the L1 error of the target marginal is below this
    int max_iterations = 100;     // Sinkhorn iterations at the final ε
};
// At the paper's blur (0.01) on images, Sinkhorn converges slowly once annealed (measured at 32²: marginal
// error 0.065 after the annealing, 0.023 after 100 more iterations, 0.011 after 1000); GeomLoss, which the
// paper used, stops after the annealing. Each iteration costs two passes over the n × m costs.

struct SinkhornResult {
    Eigen::VectorXd f, g;      // dual potentials of the source and target points
    double epsilon = 0;        // the final ε
    int annealing_steps = 0;   // iterations spent above the final ε
    int iterations = 0;        // iterations at the final ε
    double marginal_error = 0; // Σ_j |Σ_i P_ij − b_j| of the returned plan (its rows are exact)
    Points5 matched;           // barycentric projection Σ_j P_ij y_j / Σ_j P_ij of each source point
};

// Sinkhorn between the source (x, a) and the target (y, b); the weights are normalized to sum to one. The
// plan is P_ij = a_i b_j exp((f_i + g_j − C_ij)/ε). Throws Error on empty, mismatched, non-finite or
// non-positive inputs.
SinkhornResult sinkhorn(const Points5& x, const Eigen::VectorXd& a, const Points5& y,
                        const Eigen::VectorXd& b, const SinkhornOptions& options = {});

// The dense plan P (n × m) of a solution, for small problems (tests, comparisons).
Eigen::MatrixXd transport_plan(const Points5& x, const Eigen::VectorXd& a, const Points5& y,
                               const Eigen::VectorXd& b, const SinkhornResult& result,
                               const SinkhornOptions& options = {});

} // namespace penumbra
