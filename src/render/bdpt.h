#pragma once
#include "render/bdpt_subpaths.h"

namespace penumbra {

// Veach's bidirectional path tracer (render/bdpt.cpp).
class BidirectionalPathTracer final : public Integrator {
  public:
    explicit BidirectionalPathTracer(const BDPTSettings& settings) : settings_(settings) {}
    std::vector<Layer> render(const Scene& scene, const RenderOptions& options,
                              RenderStats& stats) const override;

  private:
    BDPTSettings settings_;
};

} // namespace penumbra
