// Image losses for inverse rendering. Each returns the loss value and its adjoint image ∂L/∂I, the seed of
// the reverse-mode gradient dL/dθ = Σ_pixels ∂L/∂I · dI/dθ (diff/psdr/interior.h).
#pragma once
#include "core/image.h"

#include <string>

namespace penumbra {

// Matching: paper 003's Eq. 25 between sampled paths and target pixels (diff/dpm/matching_loss.h), which only
// the methods that sample paths with screen positions (dpm-g, dpm-c) evaluate; it has no image adjoint.
enum class LossKind { L2, RelativeL2, Matching };

struct LossResult {
    double value = 0;
    Image adjoint; // ∂L/∂I per pixel and channel, same size as the image
};

// L2 = (1/3N) Σ_{pixels, channels} (I − T)²;   ∂L/∂I = 2 (I − T) / 3N.
LossResult l2_loss(const Image& image, const Image& target);
// Relative L2 = (1/3N) Σ (I − T)² / (T² + ε), ε = 0.01;   ∂L/∂I = 2 (I − T) / (3N (T² + ε)).
// ε keeps dark target pixels from dominating; the denominator uses the target, so the loss is a weighted L2.
LossResult relative_l2_loss(const Image& image, const Image& target);
// Throws Error for the matching loss (it is not a function of an image).
LossResult compute_loss(LossKind kind, const Image& image, const Image& target);

// "l2" | "rel_l2" | "matching"; throws Error otherwise.
LossKind parse_loss_kind(const std::string& name);
std::string loss_kind_name(LossKind kind);

} // namespace penumbra
