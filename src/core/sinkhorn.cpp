#include "core/sinkhorn.h"

#include "core/error.h"
#include "core/interrupt.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

namespace penumbra {

namespace {

constexpr Eigen::Index RowGrain = 16;  // rows per task; each row is computed whole, in a fixed order
constexpr float MinExponent = -80.f;   // see softmin
constexpr Eigen::Index SumChunk = 256; // float partial sums of the row's exponentials, accumulated in double

// A point cloud in the weighted cost's coordinates (xy scaled by √w), with ½‖x‖² and log of its normalized
// weights: C_ij = ½‖x_i‖² + ½‖y_j‖² − x_i·y_j.
struct Cloud {
    Points5 points;
    Eigen::VectorXd half_norm2, log_weight;
};

void check_cloud(const char* name, const Points5& points, const Eigen::VectorXd& weights) {
    const std::string what = std::string("sinkhorn: the ") + name;
    if (points.rows() == 0) throw Error(what + " is empty");
    if (weights.size() != points.rows())
        throw Error(what + " has " + std::to_string(points.rows()) + " points but " +
                    std::to_string(weights.size()) + " weights");
    for (Eigen::Index i = 0; i < points.rows(); ++i) {
        if (!points.row(i).allFinite())
            throw Error(what + "'s point " + std::to_string(i) + " is not finite");
        if (!(weights[i] > 0) || !std::isfinite(weights[i]))
            throw Error(what + "'s weight " + std::to_string(i) + " is " + std::to_string(weights[i]) +
                        " (must be positive and finite)");
    }
}

void check_options(const SinkhornOptions& o) {
    if (!(o.blur > 0) || !std::isfinite(o.blur))
        throw Error("sinkhorn: blur must be positive and finite (ε = blur²), got " + std::to_string(o.blur));
    if (!(o.scaling >= 0 && o.scaling < 1))
        throw Error("sinkhorn: scaling must be in [0, 1), got " + std::to_string(o.scaling));
    if (!(o.position_weight > 0) || !std::isfinite(o.position_weight))
        throw Error("sinkhorn: position_weight must be positive and finite, got " +
                    std::to_string(o.position_weight));
    if (!(o.tolerance >= 0)) throw Error("sinkhorn: tolerance must be non-negative");
    if (o.max_iterations < 1) throw Error("sinkhorn: max_iterations must be at least 1");
}

Cloud make_cloud(const Points5& points, const Eigen::VectorXd& weights, double sqrt_position_weight) {
    Cloud c{points, {}, {}};
    c.points.rightCols<2>() *= sqrt_position_weight;
    c.half_norm2 = 0.5 * c.points.rowwise().squaredNorm();
    c.log_weight = (weights / weights.sum()).array().log();
    return c;
}

// The log-domain Sinkhorn update (the soft-min of Cuturi 2013 and Feydy et al. 2019): f_i = −ε log Σ_j b_j
// exp((g_j − C_ij)/ε), evaluated as ½‖x_i‖² − ε LSE_j(log b_j + (g_j − ½‖y_j‖²)/ε + x_i·y_j/ε). With
// `projection`, also the barycentric projection Σ_j P_ij y_j / Σ_j P_ij of each x_i under the plan with the
// new f.
Eigen::VectorXd softmin(const Cloud& x, const Cloud& y, const Eigen::VectorXd& g, double epsilon,
                        Points5* projection) {
    check_interrupt();
    const double inv_eps = 1.0 / epsilon;
    const Eigen::ArrayXd h = y.log_weight.array() + (g - y.half_norm2).array() * inv_eps;
    const Eigen::Index n = x.points.rows(), m = y.points.rows();
    Eigen::VectorXd f(n);
    tbb::parallel_for(tbb::blocked_range<Eigen::Index>(0, n, RowGrain), [&](const auto& rows) {
        Eigen::ArrayXd s(m);
        Eigen::ArrayXf e(m);
        for (Eigen::Index i = rows.begin(); i != rows.end(); ++i) {
            const auto& yp = y.points;
            const Eigen::Matrix<double, 1, 5> c = x.points.row(i) * inv_eps;
            s = h + yp.col(0).array() * c[0] + yp.col(1).array() * c[1] + yp.col(2).array() * c[2] +
                yp.col(3).array() * c[3] + yp.col(4).array() * c[4];
            const double top = s.maxCoeff();
            // The exponent is formed in double (its terms reach 1/ε); exp of the shifted value, in [0, 1], is
            // accurate to float precision (and vectorized in float) and summed in float chunks, in double.
            // Exponents are clamped at −80 (e^−80 ≈ 2e−35 per entry, far below float precision of the sum):
            // below −87 exp is denormal, and arithmetic on denormals is ~10× slower.
            e = (s - top).cast<float>().max(MinExponent);
            e = e.exp();
            double sum = 0;
            for (Eigen::Index j = 0; j < m; j += SumChunk)
                sum += e.segment(j, std::min(SumChunk, m - j)).sum();
            f[i] = x.half_norm2[i] - epsilon * (top + std::log(sum));
            if (projection)
                for (int k = 0; k < 5; ++k)
                    (*projection)(i, k) = (e.cast<double>() * y.points.col(k).array()).sum() / sum;
        }
    });
    return f;
}

// Diagonal of the joint bounding box: the largest cost scale, where ε-scaling starts (GeomLoss).
double diameter(const Cloud& x, const Cloud& y) {
    const Eigen::Matrix<double, 1, 5> lo =
        x.points.colwise().minCoeff().cwiseMin(y.points.colwise().minCoeff());
    const Eigen::Matrix<double, 1, 5> hi =
        x.points.colwise().maxCoeff().cwiseMax(y.points.colwise().maxCoeff());
    return (hi - lo).norm();
}

// ε-scaling (GeomLoss's schedule): blur from the diameter down to the target by `scaling` per step.
std::vector<double> annealing_schedule(double diameter, const SinkhornOptions& o) {
    std::vector<double> eps;
    if (o.scaling > 0)
        for (double blur = diameter; blur > o.blur; blur *= o.scaling)
            eps.push_back(blur * blur);
    return eps;
}

} // namespace

SinkhornResult sinkhorn(const Points5& x, const Eigen::VectorXd& a, const Points5& y,
                        const Eigen::VectorXd& b, const SinkhornOptions& options) {
    check_cloud("source", x, a);
    check_cloud("target", y, b);
    check_options(options);
    const double sqrt_w = std::sqrt(options.position_weight);
    const Cloud source = make_cloud(x, a, sqrt_w), target = make_cloud(y, b, sqrt_w);

    SinkhornResult r;
    r.epsilon = options.blur * options.blur;
    r.f = Eigen::VectorXd::Zero(x.rows());
    r.g = Eigen::VectorXd::Zero(y.rows());
    for (double eps : annealing_schedule(diameter(source, target), options)) {
        r.f = softmin(source, target, r.g, eps, nullptr);
        r.g = softmin(target, source, r.f, eps, nullptr);
        ++r.annealing_steps;
    }
    // Each iteration makes the rows exact (f update) and measures the columns of that plan through the g
    // update: Σ_i P_ij = b_j exp((g_j − g'_j)/ε). The returned (f, g) is the measured plan.
    const Eigen::ArrayXd b_normalized = b / b.sum();
    while (true) {
        r.f = softmin(source, target, r.g, r.epsilon, nullptr);
        const Eigen::VectorXd g_next = softmin(target, source, r.f, r.epsilon, nullptr);
        ++r.iterations;
        r.marginal_error = (b_normalized * (((r.g - g_next).array() / r.epsilon).exp() - 1).abs()).sum();
        if (!std::isfinite(r.marginal_error))
            throw Error("sinkhorn: the iteration diverged at ε = " + std::to_string(r.epsilon));
        if (r.marginal_error < options.tolerance || r.iterations >= options.max_iterations) break;
        r.g = g_next;
    }
    r.matched.resize(x.rows(), 5);
    softmin(source, target, r.g, r.epsilon, &r.matched);
    r.matched.rightCols<2>() /= sqrt_w;
    return r;
}

Eigen::MatrixXd transport_plan(const Points5& x, const Eigen::VectorXd& a, const Points5& y,
                               const Eigen::VectorXd& b, const SinkhornResult& result,
                               const SinkhornOptions& options) {
    check_cloud("source", x, a);
    check_cloud("target", y, b);
    if (result.f.size() != x.rows() || result.g.size() != y.rows())
        throw Error("transport_plan: the potentials do not match the point clouds");
    const double sqrt_w = std::sqrt(options.position_weight);
    const Cloud source = make_cloud(x, a, sqrt_w), target = make_cloud(y, b, sqrt_w);
    Eigen::MatrixXd plan(x.rows(), y.rows());
    for (Eigen::Index j = 0; j < y.rows(); ++j)
        for (Eigen::Index i = 0; i < x.rows(); ++i) {
            const double cost = 0.5 * (source.points.row(i) - target.points.row(j)).squaredNorm();
            plan(i, j) = std::exp(source.log_weight[i] + target.log_weight[j] +
                                  (result.f[i] + result.g[j] - cost) / result.epsilon);
        }
    return plan;
}

} // namespace penumbra
