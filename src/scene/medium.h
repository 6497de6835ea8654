// Participating media declarations (homogeneous media and phase functions). Parsed now, rendered later.
#pragma once
#include "core/vector.h"
#include "scene/object.h"

#include <memory>

namespace penumbra {

class PhaseFunction : public Object {
  public:
    ObjectKind kind() const override { return ObjectKind::Phase; }
    float g = 0.f; // Henyey-Greenstein asymmetry (0 = isotropic)
};

class Medium : public Object {
  public:
    ObjectKind kind() const override { return ObjectKind::Medium; }
    Color3f sigma_t{1.f, 1.f, 1.f}; // extinction (already multiplied by `scale`)
    Color3f albedo{0.75f, 0.75f, 0.75f};
    std::shared_ptr<PhaseFunction> phase;
    // Mitsuba's `sample_emitters`: next-event estimation inside the medium (off: emitters are found by
    // phase-function sampling only). Changes the variance, not the expectation.
    bool sample_emitters = true;
};

} // namespace penumbra
