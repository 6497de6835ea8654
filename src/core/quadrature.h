// Gauss-Legendre quadrature (as Mitsuba's quad::gauss_legendre, used to tabulate microfacet albedos).
#pragma once
#include <cmath>
#include <vector>

namespace penumbra {

// Nodes x_i and weights w_i of the n-point Gauss-Legendre rule on [-1, 1]: the roots of the Legendre
// polynomial P_n (Newton's method from the guess cos(pi (i + 3/4) / (n + 1/2))) and w_i = 2 / ((1 - x_i^2)
// P_n'(x_i)^2).
inline void gauss_legendre(int n, std::vector<double>& nodes, std::vector<double>& weights) {
    nodes.assign(n, 0.0);
    weights.assign(n, 0.0);
    for (int i = 0; i < n; ++i) {
        double x = std::cos(M_PI * (i + 0.75) / (n + 0.5)), dp = 1.0;
        for (int it = 0; it < 100; ++it) {
            // P_n(x) and P_n'(x) by the three-term recurrence (k + 1) P_{k+1} = (2k + 1) x P_k - k P_{k-1}.
            double p0 = 1.0, p1 = x;
            for (int k = 1; k < n; ++k) {
                const double p2 = ((2 * k + 1) * x * p1 - k * p0) / (k + 1);
                p0 = p1;
                p1 = p2;
            }
            dp = n * (x * p1 - p0) / (x * x - 1.0);
            const double step = p1 / dp;
            x -= step;
            if (std::abs(step) < 1e-15) break;
        }
        nodes[n - 1 - i] = x;
        weights[n - 1 - i] = 2.0 / ((1.0 - x * x) * dp * dp);
    }
}

} // namespace penumbra
