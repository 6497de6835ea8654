// Adam (Kingma & Ba 2015) over a flat parameter vector split into named groups, each with its own learning
// rate and optional box bounds (values are clamped after every step, a projected Adam step).
#pragma once
#include <limits>
#include <string>
#include <vector>

namespace penumbra {

struct AdamGroup {
    std::string name;
    int offset = 0, size = 1; // the group's scalars in the flat vector
    double learning_rate = 0.01;
    double lower = -std::numeric_limits<double>::infinity();
    double upper = std::numeric_limits<double>::infinity();
    // One second moment for the whole group, the largest of its scalars' (the "uniform Adam" of Nicolet et
    // al. 2021, §5): the step keeps the gradient's direction within the group instead of a per-scalar sign.
    bool uniform = false;
};

struct AdamSettings {
    double beta1 = 0.9, beta2 = 0.999, epsilon = 1e-8;
};

class Adam {
  public:
    // Throws Error if the groups do not tile [0, dimension) or a group has lower > upper or a non-positive
    // rate.
    Adam(std::vector<AdamGroup> groups, int dimension, AdamSettings settings = {});

    // One step with gradient g (t = number of steps so far + 1):
    //   m ← β1 m + (1 − β1) g,   v ← β2 v + (1 − β2) g²,
    //   x ← clamp(x − lr · m̂ / (√v̂ + ε), lower, upper),   m̂ = m / (1 − β1^t),  v̂ = v / (1 − β2^t)
    // (a uniform group: v̂ the largest over the group).
    // `learning_rate_scale` multiplies every group's rate (for schedules).
    void step(std::vector<double>& x, const std::vector<double>& gradient, double learning_rate_scale = 1.0);
    // Clamps x into the bounds (for initial values).
    void project(std::vector<double>& x) const;

    int steps() const { return t_; }
    const std::vector<AdamGroup>& groups() const { return groups_; }

  private:
    std::vector<AdamGroup> groups_;
    AdamSettings settings_;
    std::vector<double> m_, v_;
    int t_ = 0;
};

} // namespace penumbra
