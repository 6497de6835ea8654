#include "core/image_loss.h"

#include "core/error.h"

namespace penumbra {

namespace {

constexpr double RelativeEpsilon = 0.01; // ε of the relative L2 loss

void check_sizes(const Image& image, const Image& target) {
    if (image.width != target.width || image.height != target.height)
        throw Error("loss: the image is " + std::to_string(image.width) + "x" + std::to_string(image.height) +
                    ", the target " + std::to_string(target.width) + "x" + std::to_string(target.height));
    if (image.pixels.empty()) throw Error("loss: empty image");
}

// Σ w(T) (I − T)² / 3N with the per-channel weight w, and its adjoint 2 w(T) (I − T) / 3N.
template <typename Weight> LossResult weighted_l2(const Image& image, const Image& target, Weight weight) {
    check_sizes(image, target);
    LossResult result{0.0, Image(image.width, image.height)};
    const double inv_count = 1.0 / (3.0 * double(image.pixels.size()));
    for (size_t i = 0; i < image.pixels.size(); ++i)
        for (int c = 0; c < 3; ++c) {
            const double t = target.pixels[i][c], d = double(image.pixels[i][c]) - t, w = weight(t);
            result.value += w * d * d * inv_count;
            result.adjoint.pixels[i][c] = float(2.0 * w * d * inv_count);
        }
    return result;
}

} // namespace

LossResult l2_loss(const Image& image, const Image& target) {
    return weighted_l2(image, target, [](double) { return 1.0; });
}

LossResult relative_l2_loss(const Image& image, const Image& target) {
    return weighted_l2(image, target, [](double t) { return 1.0 / (t * t + RelativeEpsilon); });
}

LossResult compute_loss(LossKind kind, const Image& image, const Image& target) {
    if (kind == LossKind::Matching)
        throw Error("the matching loss (paper 003, Eq. 25) pairs sampled paths with target pixels, not images: "
                    "use it with method dpm-g (or dpm-c)");
    return kind == LossKind::L2 ? l2_loss(image, target) : relative_l2_loss(image, target);
}

LossKind parse_loss_kind(const std::string& name) {
    if (name == "l2") return LossKind::L2;
    if (name == "rel_l2") return LossKind::RelativeL2;
    if (name == "matching") return LossKind::Matching;
    throw Error("unknown loss '" + name + "' (expected l2, rel_l2 or matching)");
}

std::string loss_kind_name(LossKind kind) {
    return kind == LossKind::L2 ? "l2" : kind == LossKind::RelativeL2 ? "rel_l2" : "matching";
}

} // namespace penumbra
