#include "core/distribution.h"

#include <algorithm>
#include <stdexcept>

namespace penumbra {

DiscreteDistribution::DiscreteDistribution(const std::vector<float>& weights) {
    if (weights.empty()) throw std::invalid_argument("DiscreteDistribution: no entries");
    cdf_.resize(weights.size() + 1);
    cdf_[0] = 0.0;
    for (size_t i = 0; i < weights.size(); ++i) {
        if (!(weights[i] >= 0.f) || !std::isfinite(weights[i]))
            throw std::invalid_argument("DiscreteDistribution: weights must be finite and non-negative");
        cdf_[i + 1] = cdf_[i] + weights[i];
    }
    const double total = cdf_.back();
    if (total <= 0.0) throw std::invalid_argument("DiscreteDistribution: all weights are zero");
    sum_ = float(total);
    pmf_.resize(weights.size());
    for (size_t i = 0; i < weights.size(); ++i) pmf_[i] = float(weights[i] / total);
    for (auto& c : cdf_) c /= total;
}

size_t DiscreteDistribution::sample(float& u) const {
    // The last i with cdf[i] <= u: a linear scan for a few entries (an emitter's triangles), else a search.
    const size_t n = pmf_.size();
    size_t i = 0;
    if (n <= 8) {
        while (i + 1 < n && cdf_[i + 1] <= double(u)) ++i;
    } else {
        auto it = std::upper_bound(cdf_.begin(), cdf_.end(), double(u));
        i = size_t(std::clamp<ptrdiff_t>(it - cdf_.begin() - 1, 0, ptrdiff_t(n) - 1));
    }
    while (pmf_[i] == 0.f && i + 1 < pmf_.size()) ++i; // never return a zero-probability entry
    const double w = cdf_[i + 1] - cdf_[i];
    u = w > 0 ? float(std::clamp((double(u) - cdf_[i]) / w, 0.0, 0.99999994)) : 0.f;
    return i;
}

Distribution2D::Distribution2D(const std::vector<float>& values, int width, int height)
    : width_(width), height_(height), values_(values) {
    if (width <= 0 || height <= 0 || values.size() != size_t(width) * height)
        throw std::invalid_argument("Distribution2D: bad dimensions");
    conditional_cdf_.resize(size_t(height) * (width + 1));
    marginal_cdf_.resize(height + 1);
    marginal_cdf_[0] = 0;
    for (int y = 0; y < height; ++y) {
        double* row = &conditional_cdf_[size_t(y) * (width + 1)];
        row[0] = 0;
        for (int x = 0; x < width; ++x) row[x + 1] = row[x] + std::max(0.f, values[size_t(y) * width + x]);
        marginal_cdf_[y + 1] = marginal_cdf_[y] + row[width];
    }
    total_ = marginal_cdf_[height];
    if (total_ <= 0) throw std::invalid_argument("Distribution2D: all values are zero");
}

static int find_interval(const double* cdf, int n, double u) {
    // Largest i in [0, n-1] with cdf[i] <= u.
    const double* it = std::upper_bound(cdf, cdf + n + 1, u);
    return std::clamp(int(it - cdf) - 1, 0, n - 1);
}

Vec2f Distribution2D::sample(const Vec2f& u, float& pdf) const {
    const int y = find_interval(marginal_cdf_.data(), height_, u.y * total_);
    const double* row = &conditional_cdf_[size_t(y) * (width_ + 1)];
    const double row_sum = row[width_];
    const double dy = (u.y * total_ - marginal_cdf_[y]) / std::max(row_sum, 1e-300);
    const int x = find_interval(row, width_, u.x * row_sum);
    const double cell = row[x + 1] - row[x];
    const double dx = cell > 0 ? (u.x * row_sum - row[x]) / cell : 0.5;
    pdf = float(values_[size_t(y) * width_ + x] * double(width_) * height_ / total_);
    return {float(std::clamp((x + dx) / width_, 0.0, 1.0)), float(std::clamp((y + dy) / height_, 0.0, 1.0))};
}

float Distribution2D::pdf(const Vec2f& p) const {
    const int x = std::clamp(int(p.x * width_), 0, width_ - 1);
    const int y = std::clamp(int(p.y * height_), 0, height_ - 1);
    return float(std::max(0.f, values_[size_t(y) * width_ + x]) * double(width_) * height_ / total_);
}

} // namespace penumbra
