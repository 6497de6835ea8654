#pragma once
#include "render/bdpt_subpaths.h"

namespace penumbra {

// Veach's bidirectional path tracer (render/bdpt.cpp).
class BidirectionalPathTracer final : public Integrator {
  public:
    explicit BidirectionalPathTracer(const Properties& props);
    std::vector<Layer> render(const Scene& scene, const RenderOptions& options,
                              RenderStats& stats) const override;
    const BDPTSettings& settings() const { return settings_; }

  private:
    BDPTSettings settings_;
};

} // namespace penumbra
