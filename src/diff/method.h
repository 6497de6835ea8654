// One front for every derivative method. A method (psdr, paths, and later was, war, war-bdpt, dpm-c, dpm-g)
// has a name, declares its options, and computes
//   derivative   forward mode: dI/dθ along params.direction(), with per-pixel standard errors from batches;
//   gradient     reverse mode: dL/dθ for every enabled parameter scalar, given an adjoint image ∂L/∂I;
//   loss_gradient  the same for an image loss against a target (by default: a primal render with its own
//                samples gives the loss and its adjoint, then gradient()).
// The command line (`penumbra derivative | gradient | optimize`) and the Python module reach methods only
// through derivative_methods(): a method registered there appears in both fronts, its options as `--name
// value` flags (bool options: `--name`) and as Python keyword arguments (`-` spelled `_`).
#pragma once
#include "core/image.h"
#include "core/image_loss.h"
#include "diff/parameters.h"
#include "diff/result.h"

#include <cstdint>
#include <functional>
#include <limits>
#include <map>
#include <memory>
#include <string>
#include <vector>

namespace penumbra {

struct MethodOption {
    enum class Type { Int, Float, Bool, String };
    std::string name; // the CLI flag without dashes ("primary-spp"); Python: primary_spp
    Type type = Type::Int;
    std::string help;
    std::vector<std::string> choices; // String: the allowed values (empty: any)
    double min = -std::numeric_limits<double>::infinity(), max = std::numeric_limits<double>::infinity();
};

// The options a user gave, as text, checked against the method's declarations by make_method().
class MethodOptions {
  public:
    void set(const std::string& name, const std::string& value) { values_[name] = value; }
    bool has(const std::string& name) const { return values_.count(name) > 0; }
    int get_int(const std::string& name, int fallback) const;
    double get_float(const std::string& name, double fallback) const;
    bool get_bool(const std::string& name, bool fallback) const;
    std::string get_string(const std::string& name, const std::string& fallback) const;
    const std::map<std::string, std::string>& values() const { return values_; }

  private:
    std::map<std::string, std::string> values_;
};

// What every method is run with.
struct MethodRun {
    int spp = 64;    // samples per pixel in total (a method splits them over its terms and passes)
    int batches = 1; // derivative: independent batches giving per-pixel standard errors
    uint64_t seed = 0;
    int threads = 0;      // 0 = all
    bool verbose = false; // report calibrations and costs on stderr
    const Image* importance =
        nullptr; // derivative: a pixel importance |∂L/∂I| a method may sample by (or null)
    std::function<void(float)> progress;
};

// The NaN policy, one rule for every method: a sample whose value or derivative is not finite is left out of
// the estimate and counted (cost.dropped); the front adds a non-zero count to the result's warnings, which
// every front shows (the CLI's stderr and JSON, Python's UserWarning, optimize's log).
class DerivativeMethod {
  public:
    virtual ~DerivativeMethod() = default;
    DerivativeImage derivative(const Scene& scene, const Parameters& params, const MethodRun& run);
    Gradient gradient(const Scene& scene, const Parameters& params, const Image& adjoint,
                      const MethodRun& run);
    Gradient loss_gradient(const Scene& scene, const Parameters& params, const Image& target, LossKind loss,
                           const MethodRun& run);

  protected:
    // What a method computes. A method object may keep what it calibrated on its first call (psdr: the split
    // of the budget over its terms) and reuse it while the sensor, its film and the parameter dimension stay
    // the same (an optimization loop).
    virtual DerivativeImage estimate_derivative(const Scene& scene, const Parameters& params,
                                                const MethodRun& run) = 0;
    virtual Gradient estimate_gradient(const Scene& scene, const Parameters& params, const Image& adjoint,
                                       const MethodRun& run) = 0;
    // By default a primal render with its own samples gives the loss and its adjoint, then
    // estimate_gradient().
    virtual Gradient estimate_loss_gradient(const Scene& scene, const Parameters& params, const Image& target,
                                            LossKind loss, const MethodRun& run);
};

struct MethodInfo {
    std::string name, help;
    std::vector<MethodOption> options;
    std::function<std::unique_ptr<DerivativeMethod>(const MethodOptions&)> make;
};

// Every registered method, psdr first (the default).
const std::vector<MethodInfo>& derivative_methods();
// Throws Error naming the known methods.
const MethodInfo& find_method(const std::string& name);
// Checks every given option against the method's declarations (unknown name: an Error naming the methods that
// have it; wrong type, range or choice: an Error naming the option) and builds the method.
std::unique_ptr<DerivativeMethod> make_method(const std::string& name, const MethodOptions& options);

// The methods registered in derivative_methods(), one per file.
MethodInfo interior_method_info();
MethodInfo psdr_method_info();
MethodInfo paths_method_info();
MethodInfo was_method_info();
MethodInfo war_method_info();
MethodInfo war_bdpt_method_info();
MethodInfo dpm_c_method_info();
MethodInfo dpm_g_method_info();

} // namespace penumbra
