// Discrete and piecewise-constant distributions for importance sampling (emitters, triangles, envmaps).
#pragma once
#include "core/vector.h"

#include <vector>

namespace penumbra {

// Discrete distribution over n entries proportional to non-negative weights.
class DiscreteDistribution {
public:
    DiscreteDistribution() = default;
    explicit DiscreteDistribution(const std::vector<float>& weights);
    size_t size() const { return pmf_.size(); }
    float sum() const { return sum_; }
    float pmf(size_t i) const { return pmf_[i]; }
    // Returns the index; `u` is rescaled in place to a fresh uniform sample (sample reuse).
    size_t sample(float& u) const;

private:
    std::vector<float> pmf_;
    std::vector<double> cdf_;
    float sum_ = 0.f;
};

// Piecewise-constant 2D density over [0,1]^2 on a width x height grid (marginal in y, conditional in x).
class Distribution2D {
public:
    Distribution2D() = default;
    Distribution2D(const std::vector<float>& values, int width, int height);
    // Returns a point in [0,1]^2 and its density with respect to the unit square.
    Vec2f sample(const Vec2f& u, float& pdf) const;
    float pdf(const Vec2f& p) const;
    bool empty() const { return width_ == 0; }

private:
    int width_ = 0, height_ = 0;
    std::vector<float> values_;
    std::vector<double> marginal_cdf_;
    std::vector<double> conditional_cdf_; // height_ rows of width_+1
    double total_ = 0;
};

} // namespace penumbra
