// The method `was`: warped-area sampling of paper 004 (diff/was/warped_area.h) behind the common front of
// diff/method.h. One term: the whole derivative (interior and boundary together).
#include "diff/method_adapter.h"
#include "diff/was/warped_area.h"

namespace penumbra {

namespace {

class WasMethod final : public DerivativeMethod {
  public:
    explicit WasMethod(const MethodOptions& o) {
        base_.warp.unbiased = o.get_bool("was-unbiased", false);
        base_.warp.aux_count = o.get_int("was-aux", base_.warp.aux_count);
        base_.warp.weight.kappa = float(o.get_float("was-kappa", base_.warp.weight.kappa));
        base_.warp.antithetic = !o.get_bool("no-antithetic", false);
        base_.control_variate = !o.get_bool("no-control-variate", false);
    }

  protected:
    DerivativeImage estimate_derivative(const Scene& scene, const Parameters& params,
                                        const MethodRun& run) override {
        return was_derivative(scene, params, run_options(base_, scene, run, run.batches));
    }

    Gradient estimate_gradient(const Scene& scene, const Parameters& params, const Image& adjoint,
                               const MethodRun& run) override {
        return was_gradient(scene, params, adjoint, run_options(base_, scene, run, 1));
    }

  private:
    WasOptions base_;
};

} // namespace

MethodInfo was_method_info() {
    using Type = MethodOption::Type;
    return {
        "was",
        "warped-area sampling of paper 004: boundary derivatives from auxiliary rays at every path vertex, "
        "no edge sampling (surfaces)",
        {{"was-unbiased",
          Type::Bool,
          "Russian-roulette debiasing of the warp's normalization (Algorithm 3) instead of a fixed N'",
          {}},
         {"was-aux",
          Type::Int,
          "auxiliary rays per warped direction N' (default 32; the paper's 8 is biased, "
          "docs/warped-area-sampling.md)",
          {},
          2,
          4096},
         {"was-kappa",
          Type::Float,
          "concentration of the vMF auxiliary rays and of the harmonic weights' distance (default 1e4, the "
          "paper's; larger: less bias, heavier tails)",
          {},
          1.0,
          1e8},
         {"no-antithetic", Type::Bool, "independent auxiliary samples instead of antithetic pairs", {}},
         {"no-control-variate", Type::Bool, "no control variate for the pixel filter's gradient term", {}}},
        [](const MethodOptions& o) { return std::make_unique<WasMethod>(o); }};
}

} // namespace penumbra
