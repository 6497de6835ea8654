#include "diff/dpm/matching_loss.h"

#include "core/error.h"

#include <string>

namespace penumbra {

namespace {

void check_samples(const char* name, const ScreenSamples& s) {
    if (s.position.rows() != s.colour.rows())
        throw Error(std::string("matching loss: the ") + name + " have " + std::to_string(s.position.rows()) +
                    " positions but " + std::to_string(s.colour.rows()) + " colours");
    if (!s.position.allFinite() || !s.colour.allFinite())
        throw Error(std::string("matching loss: the ") + name + " hold a non-finite value");
}

} // namespace

MatchingLossResult matching_loss(const ScreenSamples& paths, const ScreenSamples& targets, double lambda1,
                                 double lambda2) {
    check_samples("paths", paths);
    check_samples("targets", targets);
    if (paths.position.rows() == 0) throw Error("matching loss: no paths");
    if (targets.position.rows() != paths.position.rows())
        throw Error("matching loss: " + std::to_string(paths.position.rows()) + " paths but " +
                    std::to_string(targets.position.rows()) + " matched targets");
    const double inv_n = 1.0 / double(paths.position.rows());
    const Eigen::MatrixX2d dp = paths.position - targets.position;
    const Eigen::MatrixX3d dI = paths.colour - targets.colour;
    MatchingLossResult r;
    r.value = inv_n * (lambda1 * dp.squaredNorm() + lambda2 * dI.squaredNorm());
    r.d_position = (2 * lambda1 * inv_n) * dp;
    r.d_colour = (2 * lambda2 * inv_n) * dI;
    return r;
}

ScreenSamples image_samples(const Image& image) {
    if (image.pixels.empty()) throw Error("matching loss: empty image");
    const Eigen::Index n = Eigen::Index(image.pixels.size());
    ScreenSamples s{Eigen::MatrixX2d(n, 2), Eigen::MatrixX3d(n, 3)};
    for (int y = 0; y < image.height; ++y)
        for (int x = 0; x < image.width; ++x) {
            const Eigen::Index i = Eigen::Index(y) * image.width + x;
            s.position(i, 0) = (x + 0.5) / image.width;
            s.position(i, 1) = (y + 0.5) / image.height;
            for (int c = 0; c < 3; ++c)
                s.colour(i, c) = image.at(x, y)[c];
        }
    return s;
}

Points5 matching_points(const ScreenSamples& samples) {
    check_samples("samples", samples);
    Points5 p(samples.position.rows(), 5);
    p.leftCols<3>() = samples.colour.cwiseMax(0.0).cwiseMin(1.0);
    p.rightCols<2>() = samples.position;
    return p;
}

ScreenSamples match_to_image(const ScreenSamples& samples, const Eigen::VectorXd& weights,
                             const Image& target, const SinkhornOptions& options) {
    const ScreenSamples pixels = image_samples(target);
    const Points5 y = matching_points(pixels);
    const SinkhornResult r =
        sinkhorn(matching_points(samples), weights, y, Eigen::VectorXd::Ones(y.rows()), options);
    return {r.matched.rightCols<2>(), r.matched.leftCols<3>()};
}

ScreenSamples match_image_debiased(const Image& image, const Image& target, const SinkhornOptions& options) {
    const ScreenSamples pixels = image_samples(image);
    const Eigen::VectorXd uniform = Eigen::VectorXd::Ones(pixels.position.rows());
    const ScreenSamples to_target = match_to_image(pixels, uniform, target, options);
    const ScreenSamples to_self = match_to_image(pixels, uniform, image, options);
    ScreenSamples matched = pixels;
    matched.position += to_target.position - to_self.position;
    matched.colour += to_target.colour - to_self.colour;
    return matched;
}

MatchingLossResult image_matching_loss(const Image& image, const Image& target,
                                       const SinkhornOptions& options) {
    return matching_loss(image_samples(image), match_image_debiased(image, target, options));
}

Image SplitImage::whole() const {
    if (first.width != second.width || first.height != second.height)
        throw Error("matching loss: the halves of the image differ in size");
    if (first_passes <= 0 || second_passes <= 0)
        throw Error("matching loss: a half of the image has no passes");
    const float w1 = float(first_passes) / float(first_passes + second_passes), w2 = 1.f - w1;
    Image out(first.width, first.height);
    for (size_t i = 0; i < out.pixels.size(); ++i)
        out.pixels[i] = first.pixels[i] * w1 + second.pixels[i] * w2;
    return out;
}

MatchingLossResult jackknife_matching_loss(const SplitImage& image, const Image& target,
                                           const SinkhornOptions& options) {
    const double n1 = image.first_passes, n2 = image.second_passes, n = n1 + n2;
    const double w = -1.0 / (n * (1.0 / n1 + 1.0 / n2) - 2.0), w0 = 1.0 - 2.0 * w;
    MatchingLossResult r = image_matching_loss(image.whole(), target, options);
    const MatchingLossResult a = image_matching_loss(image.first, target, options);
    const MatchingLossResult b = image_matching_loss(image.second, target, options);
    r.d_position = w0 * r.d_position + w * (a.d_position + b.d_position);
    r.d_colour = w0 * r.d_colour + w * (a.d_colour + b.d_colour);
    return r;
}

} // namespace penumbra
