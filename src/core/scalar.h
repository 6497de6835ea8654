// The scalar types in which physics code is instantiated: float for rendering, Var (src/core/var.h) for the
// differentiable estimators. Interfaces expand PENUMBRA_FOR_EACH_SCALAR into one virtual method per type.
#pragma once
#include "core/var.h"

#define PENUMBRA_FOR_EACH_SCALAR(X) X(float) X(Var)
