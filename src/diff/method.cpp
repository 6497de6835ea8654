#include "diff/method.h"

#include "core/error.h"
#include "render/render.h"

#include <chrono>
#include <cmath>

namespace penumbra {

namespace {

// The declaration of `name` in `info`, or null.
const MethodOption* declared(const MethodInfo& info, const std::string& name) {
    for (const MethodOption& o : info.options)
        if (o.name == name) return &o;
    return nullptr;
}

[[noreturn]] void bad_value(const std::string& method, const std::string& name, const std::string& value,
                            const std::string& expected) {
    throw Error("method " + method + ": option '" + name + "' = '" + value + "': expected " + expected);
}

bool parse_bool(const std::string& text, bool& out) {
    if (text == "true" || text == "1" || text == "True") return out = true, true;
    if (text == "false" || text == "0" || text == "False") return out = false, true;
    return false;
}

// Checks one given option's value against its declaration.
void check_value(const std::string& method, const MethodOption& o, const std::string& value) {
    using Type = MethodOption::Type;
    if (o.type == Type::Bool) {
        bool b;
        if (!parse_bool(value, b)) bad_value(method, o.name, value, "true or false");
        return;
    }
    if (o.type == Type::String) {
        if (o.choices.empty()) return;
        std::string list;
        for (const std::string& c : o.choices) {
            if (c == value) return;
            list += (list.empty() ? "" : ", ") + c;
        }
        bad_value(method, o.name, value, "one of " + list);
    }
    size_t used = 0;
    double v = 0;
    try {
        v = o.type == Type::Int ? double(std::stoll(value, &used)) : std::stod(value, &used);
    } catch (const std::exception&) {
        used = 0;
    }
    if (used == 0 || used != value.size() || !std::isfinite(v))
        bad_value(method, o.name, value, o.type == Type::Int ? "an integer" : "a finite number");
    if (v < o.min || v > o.max) {
        char range[96];
        std::snprintf(range, sizeof(range), "a value in [%g, %g]", o.min, o.max);
        bad_value(method, o.name, value, range);
    }
}

// The NaN policy's report (diff/method.h): the count of dropped samples as a warning.
template <typename Result> Result reported(Result result) {
    if (result.cost.dropped > 0)
        result.warnings.push_back(
            std::to_string(result.cost.dropped) +
            " sample(s) with a non-finite value or derivative were left out of the estimate");
    return result;
}

} // namespace

int MethodOptions::get_int(const std::string& name, int fallback) const {
    auto it = values_.find(name);
    return it == values_.end() ? fallback : std::stoi(it->second);
}

double MethodOptions::get_float(const std::string& name, double fallback) const {
    auto it = values_.find(name);
    return it == values_.end() ? fallback : std::stod(it->second);
}

bool MethodOptions::get_bool(const std::string& name, bool fallback) const {
    auto it = values_.find(name);
    bool b = fallback;
    if (it != values_.end()) parse_bool(it->second, b);
    return b;
}

std::string MethodOptions::get_string(const std::string& name, const std::string& fallback) const {
    auto it = values_.find(name);
    return it == values_.end() ? fallback : it->second;
}

DerivativeImage DerivativeMethod::derivative(const Scene& scene, const Parameters& params,
                                             const MethodRun& run) {
    return reported(estimate_derivative(scene, params, run));
}

Gradient DerivativeMethod::gradient(const Scene& scene, const Parameters& params, const Image& adjoint,
                                    const MethodRun& run) {
    return reported(estimate_gradient(scene, params, adjoint, run));
}

Gradient DerivativeMethod::loss_gradient(const Scene& scene, const Parameters& params, const Image& target,
                                         LossKind loss, const MethodRun& run) {
    return reported(estimate_loss_gradient(scene, params, target, loss, run));
}

Gradient DerivativeMethod::estimate_loss_gradient(const Scene& scene, const Parameters& params,
                                                  const Image& target, LossKind loss, const MethodRun& run) {
    const auto start = std::chrono::steady_clock::now();
    // The primal takes its own samples: for a nonlinear loss, E[∂L/∂I(Î)] · E[dÎ/dθ] needs independence.
    RenderOptions ro;
    ro.spp = run.spp;
    ro.seed = run.seed ^ 0xD1B54A32D192ED03ULL;
    ro.threads = run.threads;
    const Image primal = render(scene, ro);
    if (primal.width != target.width || primal.height != target.height)
        throw Error("target image is " + std::to_string(target.width) + "x" + std::to_string(target.height) +
                    ", the film " + std::to_string(primal.width) + "x" + std::to_string(primal.height));
    const LossResult l = compute_loss(loss, primal, target);
    Gradient g = estimate_gradient(scene, params, l.adjoint, run);
    g.loss = l.value;
    g.primal = primal;
    g.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    return g;
}

const std::vector<MethodInfo>& derivative_methods() {
    static const std::vector<MethodInfo> methods = {psdr_method_info(), interior_method_info(),
                                                    paths_method_info(), was_method_info(),
                                                    war_method_info(), war_bdpt_method_info(),
                                                    dpm_c_method_info(), dpm_g_method_info()};
    return methods;
}

const MethodInfo& find_method(const std::string& name) {
    std::string names;
    for (const MethodInfo& m : derivative_methods()) {
        if (m.name == name) return m;
        names += (names.empty() ? "" : ", ") + m.name;
    }
    throw Error("unknown method '" + name + "' (known methods: " + names + ")");
}

std::unique_ptr<DerivativeMethod> make_method(const std::string& name, const MethodOptions& options) {
    const MethodInfo& info = find_method(name);
    for (const auto& [option, value] : options.values()) {
        if (const MethodOption* o = declared(info, option)) {
            check_value(name, *o, value);
            continue;
        }
        std::string owners;
        for (const MethodInfo& m : derivative_methods())
            if (declared(m, option)) owners += (owners.empty() ? "" : ", ") + m.name;
        throw Error("option '" + option + "' is not an option of method " + name +
                    (owners.empty() ? "" : " (it belongs to method " + owners + ")"));
    }
    return info.make(options);
}

} // namespace penumbra
