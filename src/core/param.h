// How templated physics reads a differentiable parameter: as its float value when rendering, and as a leaf of
// the AD tape (Var) when the parameter is enabled for differentiation (index >= 0).
#pragma once
#include "core/var.h"
#include "core/vector.h"

namespace penumbra {

template <typename T> inline T param_value(float value, int index) {
    if constexpr (std::is_same_v<T, Var>) return index < 0 ? Var(value) : Var::parameter(value, index);
    else return T(value);
}

// A color parameter occupying indices index, index+1, index+2.
template <typename T> inline Color3<T> param_color(const Color3f& value, int index) {
    return {param_value<T>(value.x, index), param_value<T>(value.y, index < 0 ? -1 : index + 1),
            param_value<T>(value.z, index < 0 ? -1 : index + 2)};
}

} // namespace penumbra
