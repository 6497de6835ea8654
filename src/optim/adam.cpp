#include "optim/adam.h"

#include "core/error.h"

#include <algorithm>
#include <cmath>

namespace penumbra {

Adam::Adam(std::vector<AdamGroup> groups, int dimension, AdamSettings settings)
    : groups_(std::move(groups)), settings_(settings), m_(size_t(dimension), 0.0),
      v_(size_t(dimension), 0.0) {
    std::vector<int> covered(size_t(dimension), 0);
    for (const AdamGroup& g : groups_) {
        if (g.offset < 0 || g.size <= 0 || g.offset + g.size > dimension)
            throw Error("adam: group '" + g.name + "' lies outside the parameter vector");
        if (!(g.learning_rate > 0.0))
            throw Error("adam: group '" + g.name + "' needs a positive learning rate");
        if (!(g.lower <= g.upper)) throw Error("adam: group '" + g.name + "' has lower bound > upper bound");
        for (int k = 0; k < g.size; ++k)
            covered[size_t(g.offset + k)]++;
    }
    for (int c : covered)
        if (c != 1) throw Error("adam: the groups must cover every parameter exactly once");
}

void Adam::step(std::vector<double>& x, const std::vector<double>& gradient, double learning_rate_scale) {
    if (x.size() != m_.size() || gradient.size() != m_.size())
        throw Error("adam: expected " + std::to_string(m_.size()) + " values and gradients");
    ++t_;
    const double b1 = settings_.beta1, b2 = settings_.beta2;
    const double c1 = 1.0 - std::pow(b1, t_), c2 = 1.0 - std::pow(b2, t_); // bias corrections
    for (const AdamGroup& g : groups_) {
        const double lr = g.learning_rate * learning_rate_scale;
        double v_max = 0;
        for (int k = g.offset; k < g.offset + g.size; ++k) {
            const double gk = gradient[size_t(k)];
            m_[size_t(k)] = b1 * m_[size_t(k)] + (1.0 - b1) * gk;
            v_[size_t(k)] = b2 * v_[size_t(k)] + (1.0 - b2) * gk * gk;
            v_max = std::max(v_max, v_[size_t(k)]);
        }
        for (int k = g.offset; k < g.offset + g.size; ++k) {
            const double v = g.uniform ? v_max : v_[size_t(k)];
            x[size_t(k)] -= lr * (m_[size_t(k)] / c1) / (std::sqrt(v / c2) + settings_.epsilon);
            x[size_t(k)] = std::clamp(x[size_t(k)], g.lower, g.upper);
        }
    }
}

void Adam::project(std::vector<double>& x) const {
    for (const AdamGroup& g : groups_)
        for (int k = g.offset; k < g.offset + g.size; ++k)
            x[size_t(k)] = std::clamp(x[size_t(k)], g.lower, g.upper);
}

} // namespace penumbra
