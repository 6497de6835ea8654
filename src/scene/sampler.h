// The scene's sampler object: a SamplerSpec (core/sampler.h) loaded from a <sampler> element.
#pragma once
#include "core/sampler.h"
#include "scene/object.h"

namespace penumbra {

class SamplerDesc : public Object, public SamplerSpec {
  public:
    ObjectKind kind() const override { return ObjectKind::Sampler; }
};

} // namespace penumbra
