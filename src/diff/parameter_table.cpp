#include "diff/parameter_table.h"

#include <algorithm>
#include <cmath>
#include <iomanip>
#include <set>
#include <sstream>

namespace penumbra {

namespace {

using Kind = Parameter::Kind;

// "name@cx,cy,cz" with the center printed so that it parses back to the same floats.
std::string at_center(const std::string& name, const Vec3d& center) {
    const Vec3f c(center);
    std::ostringstream os;
    os << std::setprecision(9) << name << '@' << c.x << ',' << c.y << ',' << c.z;
    return os.str();
}

// x -> c0 + t + R (x − c0) as a transform.
Transform rigid_motion(const Vec3d& c0, const Vec3d& t, const Mat3d& r) {
    const Vec3d shift = c0 + t - r * c0;
    Matrix4 m = Matrix4::identity();
    for (int i = 0; i < 3; ++i) {
        for (int j = 0; j < 3; ++j)
            m.m[i][j] = float(r.m[i][j]);
        m.m[i][3] = float(shift[i]);
    }
    return Transform(m);
}

Vec3d vec3(const float* v) { return {v[0], v[1], v[2]}; }
Vec3d vec3(const std::vector<double>& v, int offset) { return {v[offset], v[offset + 1], v[offset + 2]}; }
std::vector<float> floats(const Vec3d& v) { return {float(v.x), float(v.y), float(v.z)}; }

} // namespace

// One posed object: shapes (a shape, or an instance's copies), the sensor or a light, and its pose values.
struct ParameterTable::Pose {
    std::string owner;
    std::vector<Shape*> shapes;
    Sensor* sensor = nullptr;
    Emitter* emitter = nullptr;
    // Shapes: the reference meshes, taken when the pose first moves (until then the meshes are as loaded).
    std::vector<ShapePose> references;
    Transform reference; // sensor / light: to_world as loaded
    Vec3d c0{0.0};
    PoseValues values;

    // The current rotation / scaling center c0 + t.
    Vec3d center() const {
        return (references.empty() && !shapes.empty() ? Vec3d(bbox_center(shapes)) : c0) + values.t;
    }
    // Places the reference at `values`; returns whether geometry moved.
    bool place() {
        const Mat3d rotation = rotation_from_vector(values.r);
        if (sensor || emitter) {
            const Transform placed =
                values.zero() ? reference : rigid_motion(c0, values.t, rotation) * reference;
            if (sensor)
                sensor->set_transform(placed);
            else
                emitter->set_to_world(placed);
            return false;
        }
        if (references.empty()) {
            c0 = Vec3d(bbox_center(shapes));
            for (Shape* shape : shapes)
                references.emplace_back(*shape, c0);
        }
        for (ShapePose& pose : references) {
            pose.set(values.t, rotation, values.s);
            pose.apply();
        }
        return true;
    }
};

ParameterTable::ParameterTable(Scene& scene) : scene_(scene), params_(std::make_unique<Parameters>(scene)) {
    std::map<std::string, int> pose_index;
    for (const Parameter& p : params_->all()) {
        Entry e{p.name, p.dims.empty() ? std::vector<int>{p.size} : p.dims, p.kind != Kind::Data, p.geometry};
        Item item{&p, -1};
        // A deformation is listed (entries follow Parameters::all()) but is no part of a pose.
        if (p.kind == Kind::Deform) e.shape = {1};
        if (e.motion && p.kind != Kind::Deform) {
            e.shape = {p.kind == Kind::Scale ? 1 : 3};
            const std::string owner = p.name.substr(0, p.name.rfind('.'));
            auto [it, added] = pose_index.try_emplace(owner, int(poses_.size()));
            if (added) {
                auto pose = std::make_unique<Pose>();
                pose->owner = owner;
                pose->sensor = p.sensor ? scene.sensor.get() : nullptr;
                pose->emitter = p.emitter;
                if (p.shape) pose->shapes = p.shapes.empty() ? std::vector<Shape*>{p.shape} : p.shapes;
                if (p.sensor || p.emitter) {
                    pose->reference = p.sensor ? scene.sensor->to_world : p.emitter->to_world();
                    pose->c0 = Vec3d(pose->reference.apply_point(Vec3f(0.f)));
                }
                poses_.push_back(std::move(pose));
            }
            item.pose = it->second;
        }
        entries_.push_back(std::move(e));
        items_.push_back(item);
    }
}

ParameterTable::~ParameterTable() = default;

int ParameterTable::find(const std::string& name) const {
    const Parameter& p = params_->find(name);
    return int(&p - params_->all().data());
}

const ParameterTable::Entry& ParameterTable::entry(int index) const {
    if (index < 0 || size_t(index) >= entries_.size())
        throw Error("parameter table: no entry " + std::to_string(index) + " (it has " +
                    std::to_string(entries_.size()) + ")");
    return entries_[size_t(index)];
}

int ParameterTable::size(int entry) const {
    int n = 1;
    for (int d : this->entry(entry).shape)
        n *= d;
    return n;
}

ParameterTable::Pose& ParameterTable::pose_of(int entry) const {
    return *poses_[size_t(items_[size_t(entry)].pose)];
}

std::vector<float> ParameterTable::get(int entry) const {
    this->entry(entry);
    if (auto it = staged_.find(entry); it != staged_.end()) return it->second;
    const Parameter& p = *items_[size_t(entry)].param;
    if (p.kind == Kind::Data) return {p.data, p.data + p.size};
    if (p.kind == Kind::Deform) return {0.f};
    const Pose& pose = pose_of(entry);
    if (p.kind == Kind::Scale) return {float(pose.values.s)};
    return floats(p.kind == Kind::Translate ? pose.values.t : pose.values.r);
}

void ParameterTable::set(int entry, const float* values, size_t count) {
    const Entry& e = this->entry(entry);
    if (count != size_t(size(entry)))
        throw Error("parameter '" + e.name + "': expected " + std::to_string(size(entry)) + " values, got " +
                    std::to_string(count));
    for (size_t k = 0; k < count; ++k)
        if (!std::isfinite(values[k]))
            throw Error("parameter '" + e.name + "': value " + std::to_string(k) + " is not finite");
    // A deformation stays at its reference (0): writing the listed values back is harmless.
    if (items_[size_t(entry)].param->kind == Kind::Deform) {
        if (values[0] == 0.f) return;
        throw Error("parameter '" + e.name +
                    "': deformations cannot be set in the parameter table, only differentiated (--param)");
    }
    if (items_[size_t(entry)].param->kind == Kind::Scale && !(values[0] > -1.f))
        throw Error("parameter '" + e.name +
                    "': the scale factor 1 + s must be positive, got s = " + std::to_string(values[0]));
    staged_[entry].assign(values, values + count);
}

// The shapes whose meshes a vertex_positions parameter sets: its shape and a group shape's flattened copies.
std::vector<Shape*> ParameterTable::deformed_by(const Parameter& p) const {
    std::vector<Shape*> out{p.shape};
    for (const auto& shape : scene_.shapes)
        if (shape->group_shape == p.shape) out.push_back(shape.get());
    return out;
}

// Poses "in use" (non-zero, or with a selected motion) must not share a shape with a deformed or selected
// vertex_positions, nor with another non-zero pose: the pose's reference would not be the shape's mesh.
void ParameterTable::check(const std::vector<PoseValues>& values, std::vector<const Shape*> deformed,
                           const std::vector<int>& selected) const {
    std::set<int> seen;
    for (int entry : selected)
        if (!seen.insert(entry).second)
            throw Error("parameter '" + entries_[size_t(entry)].name + "' is selected twice");
    std::set<int> in_use;
    for (int entry : selected) {
        const Parameter& p = *items_[size_t(entry)].param;
        if (items_[size_t(entry)].pose >= 0)
            in_use.insert(items_[size_t(entry)].pose);
        else if (p.geometry && p.shape)
            for (Shape* shape : deformed_by(p))
                deformed.push_back(shape);
    }
    std::map<const Shape*, size_t> posed; // shapes of non-zero poses
    for (size_t i = 0; i < poses_.size(); ++i) {
        if (values[i].zero()) continue;
        in_use.insert(int(i));
        for (const Shape* shape : poses_[i]->shapes)
            if (auto [it, added] = posed.try_emplace(shape, i); !added)
                throw Error("parameters '" + poses_[it->second]->owner + "' and '" + poses_[i]->owner +
                            "' pose the same shape; only one of them may be non-zero");
    }
    for (int i : in_use)
        for (const Shape* shape : poses_[size_t(i)]->shapes) {
            if (std::count(deformed.begin(), deformed.end(), shape))
                throw Error("parameter '" + poses_[size_t(i)]->owner +
                            "': vertex_positions and a pose of the same shape cannot be combined");
            if (auto it = posed.find(shape); it != posed.end() && it->second != size_t(i))
                throw Error("parameter '" + poses_[size_t(i)]->owner + "' is selected while '" +
                            poses_[it->second]->owner + "', which poses the same shape, is non-zero");
        }
}

std::vector<ParameterTable::PoseValues> ParameterTable::pose_values() const {
    std::vector<PoseValues> values;
    for (const auto& pose : poses_)
        values.push_back(pose->values);
    return values;
}

void ParameterTable::apply() {
    // The poses and deformed shapes after this call; nothing changes if they cannot be combined.
    std::vector<PoseValues> next = pose_values();
    std::vector<const Shape*> deformed = deformed_;
    for (const auto& [entry, values] : staged_) {
        const Parameter& p = *items_[size_t(entry)].param;
        if (p.kind == Kind::Data) {
            if (p.geometry && p.shape)
                for (Shape* shape : deformed_by(p))
                    deformed.push_back(shape);
            continue;
        }
        PoseValues& v = next[size_t(items_[size_t(entry)].pose)];
        if (p.kind == Kind::Translate)
            v.t = vec3(values.data());
        else if (p.kind == Kind::Rotate)
            v.r = vec3(values.data());
        else
            v.s = values[0];
    }
    std::vector<int> selected;
    for (const auto& [entry, direction] : selection_)
        selected.push_back(entry);
    check(next, deformed, selected);
    // Poses that changed, placed from their references (first: a pose back at 0 restores the mesh that a
    // vertex_positions value then replaces).
    bool moved = false;
    for (size_t i = 0; i < poses_.size(); ++i) {
        Pose& pose = *poses_[i];
        if (pose.values == next[i]) continue;
        pose.values = next[i];
        moved |= pose.place();
    }
    // Data values, written without rebuilding the BVH.
    std::vector<std::pair<std::string, std::vector<float>>> data;
    std::vector<float> values;
    for (const auto& [entry, staged] : staged_) {
        const Parameter& p = *items_[size_t(entry)].param;
        if (p.kind != Kind::Data) continue;
        data.emplace_back(p.name, std::vector<float>{});
        values.insert(values.end(), staged.begin(), staged.end());
        moved |= p.geometry;
    }
    params_->enable(data);
    params_->set_values(scene_, values, false);
    params_->disable_all();
    if (moved) scene_.build();
    deformed_ = deformed;
    staged_.clear();
    params_->rebase(scene_);
    enable(selection_, forward_);
}

void ParameterTable::select(const std::vector<int>& entries) {
    std::vector<std::pair<int, std::vector<float>>> directions;
    for (int entry : entries)
        directions.emplace_back(entry, std::vector<float>{});
    enable(directions, false);
}

void ParameterTable::select(const std::vector<std::pair<int, std::vector<float>>>& directions) {
    for (const auto& [entry, direction] : directions)
        if (direction.size() != size_t(size(entry)))
            throw Error("parameter '" + this->entry(entry).name + "': the direction needs " +
                        std::to_string(size(entry)) + " values, got " + std::to_string(direction.size()));
    enable(directions, true);
}

void ParameterTable::enable(const std::vector<std::pair<int, std::vector<float>>>& directions, bool forward) {
    if (!staged_.empty())
        throw Error("parameter table: staged values are not applied yet (call apply() first)");
    std::vector<int> entries;
    for (const auto& [entry, direction] : directions) {
        if (this->entry(entry).motion && items_[size_t(entry)].param->kind == Kind::Deform)
            throw Error("parameter '" + entries_[size_t(entry)].name +
                        "': deformations cannot be selected in the parameter table (use --param)");
        entries.push_back(entry);
    }
    check(pose_values(), deformed_, entries);
    // Translate and rotate: one motion per world axis; rotations and scaling about the current center c0 + t.
    std::vector<std::pair<std::string, std::vector<float>>> selection;
    std::vector<float> direction;
    std::vector<Selected> selected;
    int offset = 0;
    for (const auto& [entry, dir] : directions) {
        const Parameter& p = *items_[size_t(entry)].param;
        selected.push_back({entry, offset});
        if (p.kind == Kind::Data) {
            selection.emplace_back(p.name, std::vector<float>{});
            direction.insert(direction.end(), dir.begin(), dir.end());
            offset += p.size;
            continue;
        }
        const Pose& pose = pose_of(entry);
        const std::string name = p.kind == Kind::Translate || pose.sensor || pose.emitter
                                     ? p.name
                                     : at_center(p.name, pose.center());
        if (p.kind == Kind::Scale) {
            selection.emplace_back(name, std::vector<float>{});
            if (forward) direction.push_back(float(dir[0] / (1.0 + pose.values.s)));
            offset += 1;
            continue;
        }
        for (int k = 0; k < 3; ++k)
            selection.emplace_back(
                name, std::vector<float>{k == 0 ? 1.f : 0.f, k == 1 ? 1.f : 0.f, k == 2 ? 1.f : 0.f});
        if (forward) {
            const Vec3d v(dir[0], dir[1], dir[2]);
            const std::vector<float> d =
                floats(p.kind == Kind::Translate ? v : left_jacobian(pose.values.r) * v);
            direction.insert(direction.end(), d.begin(), d.end());
        }
        offset += 3;
    }
    params_->enable(selection);
    if (forward) params_->set_direction(direction);
    selection_ = directions;
    forward_ = forward;
    selected_ = selected;
}

std::vector<std::vector<double>> ParameterTable::chain(const std::vector<double>& raw) const {
    if (raw.size() != size_t(params_->dimension()))
        throw Error("parameter table: the gradient has " + std::to_string(raw.size()) + " values, expected " +
                    std::to_string(params_->dimension()));
    std::vector<std::vector<double>> out;
    for (const Selected& sel : selected_) {
        const Parameter& p = *items_[size_t(sel.entry)].param;
        if (p.kind == Kind::Data) {
            out.emplace_back(raw.begin() + sel.offset, raw.begin() + sel.offset + p.size);
            continue;
        }
        const Pose& pose = pose_of(sel.entry);
        if (p.kind == Kind::Scale) {
            out.push_back({raw[size_t(sel.offset)] / (1.0 + pose.values.s)});
            continue;
        }
        const Vec3d g = vec3(raw, sel.offset);
        const Vec3d d = p.kind == Kind::Translate ? g : left_jacobian(pose.values.r).transpose() * g;
        out.push_back({d.x, d.y, d.z});
    }
    return out;
}

} // namespace penumbra
