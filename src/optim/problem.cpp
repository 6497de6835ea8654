#include "optim/problem.h"

#include "core/error.h"

#include <cmath>
#include <map>
#include <set>
#include <span>

namespace penumbra {

namespace {

constexpr double Degree = M_PI / 180.0;

Vec3d vec3(const std::vector<double>& x, int offset) { return {x[offset], x[offset + 1], x[offset + 2]}; }

void put(std::vector<double>& x, int offset, const Vec3d& v) {
    x[size_t(offset)] = v.x, x[size_t(offset) + 1] = v.y, x[size_t(offset) + 2] = v.z;
}

} // namespace

double relative_distance(const std::vector<double>& a, const std::vector<double>& b) {
    double d2 = 0, b2 = 0;
    for (size_t k = 0; k < a.size(); ++k)
        d2 += (a[k] - b[k]) * (a[k] - b[k]), b2 += b[k] * b[k];
    return b2 > 0 ? std::sqrt(d2 / b2) : std::sqrt(d2);
}

InverseProblem::InverseProblem(Scene& scene, const std::vector<OptimizedParameter>& parameters)
    : scene_(scene), params_(std::make_unique<Parameters>(scene)) {
    std::set<std::string> names;
    std::map<const Shape*, int> pose_of;
    std::vector<std::string> pose_names; // the shape's name, the prefix of its motions
    std::set<const Shape*> deformed;     // shapes whose vertex_positions are optimized
    std::map<const Shape*, int> deformation_of;
    std::vector<std::string> handle_names; // <shape>.deform@cx,cy,cz per Deform entry, in order
    int data_dimension = 0;
    for (const OptimizedParameter& op : parameters) {
        if (!names.insert(op.name).second) throw Error("parameter '" + op.name + "' is optimized twice");
        const auto [base_name, center] = split_motion_center(op.name);
        const Parameter& p = params_->find(base_name);
        if (center && p.kind != Parameter::Kind::Deform)
            throw Error("parameter '" + op.name + "': a center (@x,y,z) applies to deformation handles only");
        Entry e{op.name, Kind::Data, dimension_, p.size, 0, -1, op.learning_rate, op.lower, op.upper};
        if (p.kind == Parameter::Kind::Data) {
            e.param_offset = data_dimension;
            data_dimension += p.size;
            data_values_.insert(data_values_.end(), p.data, p.data + p.size);
            data_selection_.emplace_back(op.name, std::vector<float>{});
            if (p.geometry && p.shape) {
                deformed.insert(p.shape);
                e.shape = p.shape;
            }
            if (op.large_steps_lambda > 0) {
                if (!e.shape || size_t(p.size) != 3 * e.shape->mesh.vertex_count())
                    throw Error(
                        "parameter '" + op.name +
                        "': the large-steps parameterization applies to a shape's vertex_positions only");
                if (std::isfinite(op.lower) || std::isfinite(op.upper))
                    throw Error("parameter '" + op.name +
                                "': the large-steps parameterization takes no bounds");
                if (!op.free.empty() && op.free.size() != 3)
                    throw Error("parameter '" + op.name +
                                "': the large-steps parameterization takes a 'free' mask of 3 components "
                                "only (x, y, z of every vertex)");
                e.uniform_adam = op.uniform_adam;
                e.large_steps = std::make_shared<const LargeSteps>(
                    e.shape->mesh.indices, int(e.shape->mesh.vertex_count()), op.large_steps_lambda);
            }
        } else {
            if (op.large_steps_lambda > 0)
                throw Error("parameter '" + op.name +
                            "': the large-steps parameterization applies to a shape's vertex_positions only");
            if (p.sensor || p.emitter)
                throw Error("parameter '" + op.name +
                            "': camera motions and light motions cannot be optimized, only shape poses");
            if (p.kind == Parameter::Kind::Deform) {
                e.kind = Kind::Deform;
                e.size = 3;
                auto [it, added] = deformation_of.try_emplace(p.shape, int(deformations_.size()));
                if (added) deformations_.emplace_back(*p.shape);
                ShapeDeformation& d = deformations_[size_t(it->second)];
                e.deformation = it->second;
                e.handle = d.add_handle(center ? *center : d.center());
                const Vec3f c = d.handle_center(e.handle);
                handle_names.push_back(base_name + "@" + std::to_string(c.x) + "," + std::to_string(c.y) + "," +
                                       std::to_string(c.z));
                dimension_ += e.size;
                entries_.push_back(e);
                continue;
            }
            if (p.kind == Parameter::Kind::Scale)
                throw Error("parameter '" + op.name +
                            "': scaling cannot be optimized; a pose is <shape>.translate and <shape>.rotate");
            e.kind = p.kind == Parameter::Kind::Translate ? Kind::Translate : Kind::Rotate;
            e.size = 3;
            if (e.kind == Kind::Rotate && (std::isfinite(op.lower) || std::isfinite(op.upper)))
                throw Error("parameter '" + op.name + "': a rotation takes no bounds");
            auto [it, added] = pose_of.try_emplace(p.shape, int(poses_.size()));
            if (added) {
                poses_.emplace_back(*p.shape);
                pose_names.push_back(op.name.substr(0, op.name.rfind('.')));
            }
            e.pose = it->second;
        }
        dimension_ += e.size;
        entries_.push_back(e);
    }
    for (size_t i = 0; i < entries_.size(); ++i) {
        Entry& e = entries_[i];
        const std::vector<bool>& free = parameters[i].free;
        if (free.empty()) {
            e.free.assign(size_t(e.size), true);
        } else if (free.size() == size_t(e.size)) {
            e.free = free;
        } else if (e.shape && free.size() == 3 && size_t(e.size) == 3 * e.shape->mesh.vertex_count()) {
            for (int k = 0; k < e.size; ++k)
                e.free.push_back(free[size_t(k % 3)]); // (x, y, z) of each vertex
        } else {
            throw Error("parameter '" + e.name + "': 'free' has " + std::to_string(free.size()) +
                        " entries for " + std::to_string(e.size) + " components" +
                        (e.shape ? " (or 3: x, y, z of every vertex)" : ""));
        }
    }
    for (const Shape* shape : deformed)
        if (pose_of.count(shape) || deformation_of.count(shape))
            throw Error("a shape's vertex_positions and its pose or deformation cannot be optimized together");
    for (const auto& [shape, index] : deformation_of)
        if (pose_of.count(shape)) throw Error("a shape's pose and its deformation cannot be optimized together");

    // Differentiation: the Data parameters, then for each posed shape six motions at θ = 0 (translate along
    // x, y, z; rotate about x, y, z), whether or not both halves of its pose are optimized: the rotation
    // gradient about the pose's center needs the translation gradient (see gradient()).
    selection_ = data_selection_;
    for (const std::string& shape : pose_names)
        for (const char* motion : {".translate", ".rotate"})
            for (int k = 0; k < 3; ++k)
                selection_.emplace_back(
                    shape + motion,
                    std::vector<float>{k == 0 ? 1.f : 0.f, k == 1 ? 1.f : 0.f, k == 2 ? 1.f : 0.f});
    // Then three deform motions (along x, y, z) per deformation handle.
    for (const std::string& handle : handle_names)
        for (int k = 0; k < 3; ++k)
            selection_.emplace_back(handle,
                                    std::vector<float>{k == 0 ? 1.f : 0.f, k == 1 ? 1.f : 0.f, k == 2 ? 1.f : 0.f});
    int handle = 0;
    for (Entry& e : entries_) {
        if (e.kind == Kind::Translate || e.kind == Kind::Rotate) e.param_offset = data_dimension + 6 * e.pose;
        if (e.kind == Kind::Deform) e.param_offset = data_dimension + 6 * int(poses_.size()) + 3 * handle++;
    }
    scene_values_ = values();
    apply();
}

InverseProblem::~InverseProblem() = default;

std::vector<AdamGroup> InverseProblem::adam_groups() const {
    std::vector<AdamGroup> groups;
    for (const Entry& e : entries_)
        groups.push_back(
            {e.name, e.offset, e.size, e.learning_rate, e.lower, e.upper, e.large_steps && e.uniform_adam});
    return groups;
}

std::vector<double> InverseProblem::values() const {
    std::vector<double> x(static_cast<size_t>(dimension_));
    for (const Entry& e : entries_) {
        if (e.kind == Kind::Data)
            std::copy(data_values_.begin() + e.param_offset, data_values_.begin() + e.param_offset + e.size,
                      x.begin() + e.offset);
        else if (e.kind == Kind::Translate)
            put(x, e.offset, poses_[size_t(e.pose)].translation());
        else if (e.kind == Kind::Deform)
            put(x, e.offset, deformations_[size_t(e.deformation)].displacement(e.handle));
        else
            put(x, e.offset, rotation_vector(poses_[size_t(e.pose)].rotation()) / Degree);
    }
    return x;
}

void InverseProblem::set_values(const std::vector<double>& x) {
    if (x.size() != size_t(dimension_))
        throw Error("expected " + std::to_string(dimension_) + " values, got " + std::to_string(x.size()));
    for (const Entry& e : entries_) {
        for (int k = 0; k < e.size; ++k)
            if (!std::isfinite(x[size_t(e.offset + k)])) throw Error("non-finite value for '" + e.name + "'");
        ShapePose* pose = e.pose >= 0 ? &poses_[size_t(e.pose)] : nullptr;
        if (e.kind == Kind::Data)
            std::copy(x.begin() + e.offset, x.begin() + e.offset + e.size,
                      data_values_.begin() + e.param_offset);
        else if (e.kind == Kind::Translate)
            pose->set(vec3(x, e.offset), pose->rotation());
        else if (e.kind == Kind::Deform)
            deformations_[size_t(e.deformation)].set(e.handle, vec3(x, e.offset));
        else
            pose->set(pose->translation(), rotation_from_vector(vec3(x, e.offset) * Degree));
    }
    apply();
}

void InverseProblem::retract(const std::vector<double>& delta) {
    if (delta.size() != size_t(dimension_))
        throw Error("expected " + std::to_string(dimension_) + " increments, got " +
                    std::to_string(delta.size()));
    std::vector<double> x = values();
    for (const Entry& e : entries_) {
        if (e.kind != Kind::Rotate) {
            for (int k = 0; k < e.size; ++k)
                x[size_t(e.offset + k)] += delta[size_t(e.offset + k)];
        } else {
            const Mat3d r =
                rotation_from_vector(vec3(delta, e.offset) * Degree) * poses_[size_t(e.pose)].rotation();
            put(x, e.offset, rotation_vector(r) / Degree);
        }
    }
    set_values(x);
}

void InverseProblem::adam_step(Adam& adam, const std::vector<double>& gradient, double learning_rate_scale) {
    // Adam sees the values of Data and translations and a zero increment for each rotation; the increments it
    // returns are then composed on the left (R ← exp([ω]×) R), so its moments are in the fixed world frame.
    const std::vector<double> before = values();
    std::vector<double> x = before;
    for (const Entry& e : entries_)
        if (e.kind == Kind::Rotate) put(x, e.offset, Vec3d(0.0));
    std::vector<double> g = gradient;
    for (const Entry& e : entries_)
        for (int k = 0; k < e.size; ++k)
            if (!e.free[size_t(k)]) g[size_t(e.offset + k)] = 0.0;
    // Large steps: Adam sees u = (I + λL) x and dL/du = (I + λL)⁻¹ dL/dx; x = (I + λL)⁻¹ u after the step.
    const auto span_of = [](std::vector<double>& v, const Entry& e) {
        return std::span<double>(v.data() + e.offset, size_t(e.size));
    };
    for (const Entry& e : entries_)
        if (e.large_steps) {
            const std::vector<double> u = e.large_steps->to_latent(span_of(x, e));
            const std::vector<double> g_u = e.large_steps->latent_gradient(span_of(g, e));
            std::copy(u.begin(), u.end(), span_of(x, e).begin());
            std::copy(g_u.begin(), g_u.end(), span_of(g, e).begin());
        }
    adam.step(x, g, learning_rate_scale);
    for (const Entry& e : entries_)
        if (e.large_steps) {
            const std::vector<double> x_e = e.large_steps->from_latent(span_of(x, e));
            std::copy(x_e.begin(), x_e.end(), span_of(x, e).begin());
        }
    std::vector<double> delta(x.size());
    for (const Entry& e : entries_)
        for (int k = e.offset; k < e.offset + e.size; ++k)
            if (e.free[size_t(k - e.offset)]) // the round trip through u must not move fixed components
                delta[size_t(k)] = e.kind == Kind::Rotate ? x[size_t(k)] : x[size_t(k)] - before[size_t(k)];
    retract(delta);
}

void InverseProblem::apply() {
    params_->enable(data_selection_);
    params_->set_values(scene_, std::vector<float>(data_values_.begin(), data_values_.end()));
    for (const ShapePose& pose : poses_)
        pose.apply();
    for (const ShapeDeformation& deformation : deformations_)
        deformation.apply();
    if (!poses_.empty() || !deformations_.empty()) scene_.build();
    params_->enable(
        selection_); // after the meshes moved: the motions' centers are the current bounding boxes'
}

std::vector<double> InverseProblem::gradient(const Image& adjoint, DerivativeMethod& method,
                                             const MethodRun& run, std::string* description,
                                             uint64_t* dropped) const {
    const Gradient g = method.gradient(scene_, *params_, adjoint, run);
    if (dropped) *dropped = g.cost.dropped;
    return to_tangent(g, description);
}

std::vector<double> InverseProblem::loss_gradient(const Image& target, LossKind loss,
                                                  DerivativeMethod& method, const MethodRun& run, Gradient& g,
                                                  std::string* description) const {
    g = method.loss_gradient(scene_, *params_, target, loss, run);
    return to_tangent(g, description);
}

std::vector<double> InverseProblem::to_tangent(const Gradient& g, std::string* description) const {
    if (description) {
        *description = g.description;
        for (const std::string& w : g.warnings) *description += "; warning: " + w;
    }
    std::vector<double> out(static_cast<size_t>(dimension_));
    for (const Entry& e : entries_) {
        if (e.kind == Kind::Data) {
            std::copy(g.values.begin() + e.param_offset, g.values.begin() + e.param_offset + e.size,
                      out.begin() + e.offset);
            continue;
        }
        const Vec3d g_translate = vec3(g.values, e.param_offset);
        if (e.kind == Kind::Translate || e.kind == Kind::Deform) {
            put(out, e.offset, g_translate);
            continue;
        }
        // The rotate motions turn about the current bounding-box center c′, the pose about c = c0 + t. A
        // rotation ω about c is the rotation about c′ plus the translation ω × (c′ − c), so
        //   dL/dω|c = dL/dω|c′ + (c′ − c) × dL/dt,   then per degree.
        const ShapePose& pose = poses_[size_t(e.pose)];
        Vec3d c_prime(0.0);
        for (const Motion& m : params_->motions(&pose.shape()))
            if (m.index == e.param_offset + 3) c_prime = Vec3d(m.center);
        const Vec3d g_rotate =
            vec3(g.values, e.param_offset + 3) + cross(c_prime - pose.center(), g_translate);
        put(out, e.offset, g_rotate * Degree);
    }
    return out;
}

double InverseProblem::data_error(const std::vector<double>& truth) const {
    const std::vector<double> x = values();
    std::vector<double> a, b;
    for (const Entry& e : entries_)
        if (e.kind == Kind::Data) {
            a.insert(a.end(), x.begin() + e.offset, x.begin() + e.offset + e.size);
            b.insert(b.end(), truth.begin() + e.offset, truth.begin() + e.offset + e.size);
        }
    return a.empty() ? NAN : relative_distance(a, b);
}

double InverseProblem::entry_error(size_t entry, const std::vector<double>& truth) const {
    const Entry& e = entries_.at(entry);
    if (e.kind == Kind::Data) return NAN;
    if (e.kind == Kind::Deform)
        return norm(deformations_[size_t(e.deformation)].displacement(e.handle) - vec3(truth, e.offset));
    const ShapePose& pose = poses_[size_t(e.pose)];
    if (e.kind == Kind::Translate) return norm(pose.translation() - vec3(truth, e.offset));
    return rotation_angle(pose.rotation(), rotation_from_vector(vec3(truth, e.offset) * Degree)) / Degree;
}

double InverseProblem::translation_error(const std::vector<double>& truth) const {
    double worst = NAN;
    for (size_t i = 0; i < entries_.size(); ++i)
        if (entries_[i].kind == Kind::Translate || entries_[i].kind == Kind::Deform)
            worst = std::fmax(worst, entry_error(i, truth));
    return worst;
}

double InverseProblem::rotation_error(const std::vector<double>& truth) const {
    double worst = NAN;
    for (size_t i = 0; i < entries_.size(); ++i)
        if (entries_[i].kind == Kind::Rotate) worst = std::fmax(worst, entry_error(i, truth));
    return worst;
}

} // namespace penumbra
