// The matching loss of DPM-G (paper 003, §5.3, Eq. 25): each sampled path's screen position p_i and colour
// I_i are pulled toward the position and colour of the target pixel matched to it by entropic optimal
// transport (core/sinkhorn.h) on 5-D points (RGB clamped to [0, 1] + xy in [0, 1]², Xing et al. 2022, 2023).
// The matching is held fixed: the loss gradient w.r.t. (p_i, I_i) is what a DPM-G estimator chains with the
// screen-space positional derivatives dp/dπ (Eq. 7) and the contribution derivatives dI/dπ.
#pragma once
#include "core/image.h"
#include "core/sinkhorn.h"

namespace penumbra {

// Screen positions in [0, 1]² (x to the right, y down: pixel (x, y) has its centre at ((x+½)/W, (y+½)/H))
// and RGB colours, one per row.
struct ScreenSamples {
    Eigen::MatrixX2d position;
    Eigen::MatrixX3d colour;
};

struct MatchingLossResult {
    double value = 0;
    Eigen::MatrixX2d d_position; // ∂L/∂p_i
    Eigen::MatrixX3d d_colour;   // ∂L/∂I_i
};

// Eq. 25 of paper 003, averaged over the N paths: L = (1/N) Σ_i λ1 ‖p_i − p_target,i‖² + λ2 ‖I_i −
// I_target,i‖²; ∂L/∂p_i = 2 λ1 (p_i − p_target,i) / N, ∂L/∂I_i = 2 λ2 (I_i − I_target,i) / N.
MatchingLossResult matching_loss(const ScreenSamples& paths, const ScreenSamples& targets,
                                 double lambda1 = 0.5, double lambda2 = 0.5);

// Every pixel of an image as a screen sample (row-major, top row first).
ScreenSamples image_samples(const Image& image);

// The 5-D points (RGB clamped to [0, 1], then xy) of screen samples.
Points5 matching_points(const ScreenSamples& samples);

// The matched target (position and colour) of each sample: the barycentric projection of the entropic optimal
// transport plan from the samples (weighted by `weights`) to the target image's pixels (uniform weights). The
// matched colour is that of the target clamped to [0, 1], the space the matching is done in.
ScreenSamples match_to_image(const ScreenSamples& samples, const Eigen::VectorXd& weights,
                             const Image& target, const SinkhornOptions& options = {});

// The debiased pixel-to-pixel matching of an image to a target (the gradient of GeomLoss's Sinkhorn divergence,
// its default): the entropic plan's barycentric projection T_IT shrinks toward local means, so each pixel x of
// `image` is matched to x + T_IT(x) − T_II(x), T_II the image matched to itself (uniform weights); at
// image = target the match is the pixel itself.
ScreenSamples match_image_debiased(const Image& image, const Image& target, const SinkhornOptions& options = {});

// Eq. 25 of an image's pixels against their debiased matching (match_image_debiased).
MatchingLossResult image_matching_loss(const Image& image, const Image& target,
                                       const SinkhornOptions& options = {});

// An image rendered as two independent groups of passes: `first` the mean of n1 passes, `second` of n2.
struct SplitImage {
    Image first, second;
    int first_passes = 0, second_passes = 0;
    // The image of all the passes: (n1 Î1 + n2 Î2) / (n1 + n2).
    Image whole() const;
};

// The matching loss of a Monte Carlo image with the O(1/passes) bias of its gradient removed: the matching is
// a nonlinear function of the noisy image, so E[∂L/∂(p, I) at Î] is not ∂L/∂(p, I) at E[Î]. The split-sample
// (delete-a-group) jackknife [Quenouille 1956] of that gradient over the image's two halves: with
// E[g(Î_m)] = g(E[Î]) + a/m + O(1/m²) for an image of m passes, w0 g(Î) + w (g(Î1) + g(Î2)), w0 + 2w = 1 and
// w0/n + w (1/n1 + 1/n2) = 0, has no 1/n term (equal halves: 2 g(Î) − ½ (g(Î1) + g(Î2))). Each half needs its
// own debiased matching (four more Sinkhorn solves). The gradient is per pixel of the whole image; the value
// is the whole image's loss.
MatchingLossResult jackknife_matching_loss(const SplitImage& image, const Image& target,
                                           const SinkhornOptions& options = {});

} // namespace penumbra
