// Multiple importance sampling weights.
#pragma once
#include <cmath>

namespace penumbra {

// Power heuristic with exponent 2 (Veach 1997, Eq. 9.13), as Mitsuba 3's path and direct integrators use.
inline float mis_power(float pdf_a, float pdf_b) {
    const float a = pdf_a * pdf_a, b = pdf_b * pdf_b;
    const float w = a / (a + b);
    return std::isfinite(w) ? w : 0.f;
}

} // namespace penumbra
