// The methods `war` and `war-bdpt`: the unidirectional and bidirectional estimators of warped-area
// reparameterization in material path space (paper 000, diff/war/war.h, diff/war/war_bdpt.h) behind the common front
// of diff/method.h, with the same options. One term: the whole derivative (interior and boundary together).
#include "diff/method_adapter.h"
#include "diff/war/war_bdpt.h"

namespace penumbra {

namespace {

class WarMethod final : public DerivativeMethod {
  public:
    WarMethod(const MethodOptions& o, bool bidirectional) : bidirectional_(bidirectional) {
        WarFieldOptions& f = base_.field;
        f.aux_count = o.get_int("war-aux", f.aux_count);
        f.sigma = float(o.get_float("war-sigma", f.sigma));
        f.exponent = float(o.get_float("war-exponent", f.exponent));
        f.spread = float(o.get_float("war-spread", f.spread));
        f.antithetic = !o.get_bool("no-antithetic", false);
        f.directions.antithetic = f.antithetic;
        f.camera_directions.antithetic = f.antithetic;
    }

  protected:
    DerivativeImage estimate_derivative(const Scene& scene, const Parameters& params,
                                        const MethodRun& run) override {
        const WarOptions o = run_options(base_, scene, run, run.batches);
        return bidirectional_ ? war_bdpt_derivative(scene, params, o) : war_derivative(scene, params, o);
    }

    Gradient estimate_gradient(const Scene& scene, const Parameters& params, const Image& adjoint,
                               const MethodRun& run) override {
        const WarOptions o = run_options(base_, scene, run, 1);
        return bidirectional_ ? war_bdpt_gradient(scene, params, adjoint, o)
                              : war_gradient(scene, params, adjoint, o);
    }

  private:
    bool bidirectional_;
    WarOptions base_;
};

// The options both estimators share: the field's (paper 000's parameters) and the auxiliary points'.
std::vector<MethodOption> war_options() {
    using Type = MethodOption::Type;
    return {
        {"war-aux",
         Type::Int,
         "auxiliary points N_q per warped vertex (default 64: the consistent field is biased at 16, "
         "docs/war.md)",
         {},
         2,
         4096},
        {"war-sigma",
         Type::Float,
         "sigma of the distance D(q, p) = (1 - exp(-r^2/sigma)) / sigma, r = |q - p| / |x - y| (default "
         "0.006, the paper's)",
         {},
         1e-5,
         1.0},
        {"war-exponent",
         Type::Float,
         "exponent alpha of the weight 1 / (D^alpha + B) (default 3, the paper's)",
         {},
         1.0,
         8.0},
        {"war-spread",
         Type::Float,
         "standard deviation of the tangent-plane Gaussian of auxiliary points, in units of |x - y| "
         "(default 0.012 = 2 sigma, by measurement: docs/war.md)",
         {},
         1e-5,
         1.0},
        {"no-antithetic", Type::Bool, "independent auxiliary points instead of point-reflected pairs", {}}};
}

} // namespace

MethodInfo war_method_info() {
    return {
        "war",
        "warped-area reparameterization of paper 000: path tracing with NEE in material form, each vertex "
        "warped by a continuous velocity field (no boundary sampling but the film and pixel edges where the "
        "filters jump; surfaces)",
        war_options(), [](const MethodOptions& o) { return std::make_unique<WarMethod>(o, false); }};
}

MethodInfo war_bdpt_method_info() {
    return {"war-bdpt",
            "warped-area reparameterization of paper 000, bidirectional (Eq. 54): bdpt's strategies in "
            "material form, source and detector subpath vertices warped (surfaces, no infinite lights)",
            war_options(), [](const MethodOptions& o) { return std::make_unique<WarMethod>(o, true); }};
}

} // namespace penumbra
