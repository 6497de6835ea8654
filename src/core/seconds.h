// Wall-clock seconds elapsed since a steady-clock time point (the `seconds` of estimator results).
#pragma once
#include <chrono>

namespace penumbra {

inline double seconds_since(std::chrono::steady_clock::time_point start) {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

} // namespace penumbra
