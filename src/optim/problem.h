// The optimized quantities of an inverse problem as one flat vector, the layout Adam steps in:
//   Data parameters      their values (materials, emitters, ...),
//   <shape>.translate    t ∈ R³, world units, relative to the scene's pose,
//   <shape>.rotate       a rotation vector in degrees (axis-angle: direction = world axis, norm = angle)
//                        about the shape's bounding-box center in the scene (diff/pose.h),
//   <shape>.deform@c     the displacement θ ∈ R³ (world units) of a deformation handle at c (default: the
//                        bounding-box center), x → x + θ exp(−‖x − c‖² / 2r²) (optim/deformation.h); a shape
//                        may have several handles, not together with a pose.
// Tangent vectors (gradients, Adam steps, finite-difference directions) have the same layout; for rotations
// they are world-frame increments ω (degrees) applied on the left, R ← exp([ω]×) R.
// Gradients come from a derivative method (diff/method.h); a pose needs one with boundary terms (psdr), since
// silhouettes and shadows carry most of its signal.
#pragma once
#include "diff/method.h"
#include "diff/pose.h"
#include "optim/adam.h"
#include "optim/deformation.h"
#include "optim/large_steps.h"

#include <limits>
#include <memory>
#include <string>
#include <vector>

namespace penumbra {

struct OptimizedParameter {
    std::string name;
    std::vector<float> init; // empty: the scene's value (0 for a pose); 1 value: broadcast (Data only)
    double learning_rate = 0.01;
    double lower = -std::numeric_limits<double>::infinity(); // not allowed for rotations
    double upper = std::numeric_limits<double>::infinity();
    // Which components are optimized (empty: all; for a vertex_positions also 3 booleans, x, y, z of every
    // vertex); the others keep their init.
    std::vector<bool> free = {};
    // > 0: a <shape>.vertex_positions stepped in u = (I + λL) x, λ this value (optim/large_steps.h)
    double large_steps_lambda = 0;
    bool uniform_adam = true; // large steps: Adam with one second moment for the parameter (optim/adam.h)
};

// ‖a − b‖ / ‖b‖ (‖a − b‖ when b = 0).
double relative_distance(const std::vector<double>& a, const std::vector<double>& b);

class InverseProblem {
  public:
    enum class Kind { Data, Translate, Rotate, Deform };
    struct Entry {
        std::string name;
        Kind kind = Kind::Data;
        int offset = 0, size = 0; // in the flat vector
        int param_offset = 0;     // Data: its index in Parameters; poses: the first of 3 motion indices
        int pose = -1;            // Translate / Rotate: index into poses()
        double learning_rate = 0.01, lower = 0, upper = 0;
        int deformation = -1, handle = -1; // Deform: index into the deformations and the handle in it
        std::vector<bool> free = {};       // size components: whether each is optimized
        const Shape* shape = nullptr;      // <shape>.vertex_positions: the shape
        std::shared_ptr<const LargeSteps> large_steps = nullptr; // its large-steps parameterization, or null
        bool uniform_adam = false;                               // large steps: uniform Adam (optim/adam.h)
    };

    // Resolves the names against the scene. Throws Error for unknown names, camera motions, scaling, a
    // parameter given twice, vertex_positions together with a pose of the same shape, bounds on a rotation,
    // a `free` mask whose length is neither the parameter's number of components nor (vertex_positions) 3,
    // and a large-steps parameterization of anything but a vertex_positions, with bounds or with a mask of
    // more than 3 components (it acts on each coordinate column separately, so a per-column mask commutes
    // with it).
    InverseProblem(Scene& scene, const std::vector<OptimizedParameter>& parameters);
    ~InverseProblem();

    int dimension() const { return dimension_; }
    const std::vector<Entry>& entries() const { return entries_; }
    bool geometric() const { return !poses_.empty() || !deformations_.empty(); }
    const std::vector<ShapePose>& poses() const { return poses_; }
    std::vector<AdamGroup> adam_groups() const;

    // The scene's own values (poses: 0).
    std::vector<double> scene_values() const { return scene_values_; }
    // Current values (rotations as rotation vectors in degrees).
    std::vector<double> values() const;
    // Sets the values and moves the scene there (Data written, posed meshes rebuilt, the BVH rebuilt).
    void set_values(const std::vector<double>& x);
    // x ⊕ δ: Data and translations add δ, rotations compose on the left with exp([δ]×) (δ in degrees).
    void retract(const std::vector<double>& delta);
    // One Adam step with a gradient in the tangent layout (rotations: increments from 0, then retracted);
    // components that are not free get a zero gradient, hence no step. Large-steps entries step in
    // u = (I + λL) x with the gradient (I + λL)⁻¹ dL/dx (optim/large_steps.h).
    void adam_step(Adam& adam, const std::vector<double>& gradient, double learning_rate_scale);

    // dL/dx in the tangent layout for the adjoint ∂L/∂I at the current values, by a derivative method
    // (diff/method.h: psdr includes the boundary terms a pose needs, interior does not).
    // `description`, when given, receives the method's description of the run, `dropped` the samples it left
    // out for a non-finite value or derivative (the NaN policy, diff/method.h).
    std::vector<double> gradient(const Image& adjoint, DerivativeMethod& method, const MethodRun& run,
                                 std::string* description = nullptr, uint64_t* dropped = nullptr) const;
    // The same for a loss the method evaluates itself against the target (the matching loss of dpm-g); `g`
    // receives the method's result (its loss and primal image).
    std::vector<double> loss_gradient(const Image& target, LossKind loss, DerivativeMethod& method,
                                      const MethodRun& run, Gradient& g,
                                      std::string* description = nullptr) const;

  private:
    std::vector<double> to_tangent(const Gradient& g, std::string* description) const;

  public:
    // Errors against true values (the values() layout): ‖x − x*‖ / ‖x*‖ over Data entries; ‖t − t*‖ (scene
    // units) and the angle of R R*ᵀ (degrees) of one pose entry. NaN when there is no such entry.
    double data_error(const std::vector<double>& truth) const;
    double entry_error(size_t entry, const std::vector<double>& truth) const;
    // The largest translation / rotation error over the pose entries (NaN when there is none).
    double translation_error(const std::vector<double>& truth) const;
    double rotation_error(const std::vector<double>& truth) const;

  private:
    void apply();
    Scene& scene_;
    std::unique_ptr<Parameters> params_;
    std::vector<Entry> entries_;
    std::vector<ShapePose> poses_;
    std::vector<ShapeDeformation> deformations_;
    std::vector<std::pair<std::string, std::vector<float>>> data_selection_, selection_;
    std::vector<double> data_values_, scene_values_;
    int dimension_ = 0;
};

} // namespace penumbra
