#include "diff/parameters.h"

#include <algorithm>
#include <initializer_list>
#include <set>
#include <sstream>

namespace penumbra {

namespace {

std::string join(const std::string& prefix, const std::string& name) {
    if (name.empty()) return prefix;
    return prefix.empty() ? name : prefix + "." + name;
}

// Walks traverse() recursively, naming parameters after their owners (Mitsuba 3 conventions).
class Collector final : public ParamVisitor {
public:
    Collector(std::vector<Parameter>& out, std::set<const Object*>& seen, std::string prefix, Object* owner)
        : out_(out), seen_(seen), prefix_(std::move(prefix)), owner_(owner) {}

    void put(const std::string& name, float* values, int size, int* index, bool geometry) override {
        put_array(name, values, {size}, index, geometry);
    }
    void put_array(const std::string& name, float* values, const std::vector<int>& shape, int* index,
                   bool geometry) override {
        Parameter p;
        p.name = join(prefix_, name);
        p.data = values;
        p.size = 1;
        for (int n : shape)
            p.size *= n;
        p.dims = shape;
        p.index = index;
        p.geometry = geometry;
        p.owner = owner_;
        p.shape = dynamic_cast<Shape*>(owner_);
        out_.push_back(std::move(p));
    }
    void put_object(const std::string& name, Object* object) override { visit(object, join(prefix_, name)); }

    void visit(Object* object, const std::string& fallback_name) {
        if (!object || !seen_.insert(object).second) return;
        Collector child(out_, seen_, object->id.empty() ? fallback_name : object->id, object);
        object->traverse(child);
    }

private:
    std::vector<Parameter>& out_;
    std::set<const Object*>& seen_;
    std::string prefix_;
    Object* owner_;
};

// Levenshtein distance, for "did you mean" suggestions.
size_t edit_distance(const std::string& a, const std::string& b) {
    std::vector<size_t> row(b.size() + 1);
    for (size_t j = 0; j <= b.size(); ++j) row[j] = j;
    for (size_t i = 1; i <= a.size(); ++i) {
        size_t diag = row[0];
        row[0] = i;
        for (size_t j = 1; j <= b.size(); ++j) {
            const size_t up = row[j];
            row[j] = std::min({row[j] + 1, row[j - 1] + 1, diag + (a[i - 1] == b[j - 1] ? 0 : 1)});
            diag = up;
        }
    }
    return row[b.size()];
}

std::string shape_name(const Shape& shape, size_t index) {
    return shape.id.empty() ? "shape_" + std::to_string(index) : shape.id;
}

// The shapes a motion moves: the instance's copies, or its one shape.
std::vector<Shape*> motion_shapes(const Parameter& p) {
    return p.shapes.empty() ? std::vector<Shape*>{p.shape} : p.shapes;
}

// The shapes whose meshes change with a geometry parameter: those it moves, and the flattened copies of a
// group shape whose vertex_positions it is.
std::vector<Shape*> moved_shapes(const Parameter& p, const Scene& scene) {
    if (!p.shape || !p.geometry) return {};
    std::vector<Shape*> out = motion_shapes(p);
    if (p.kind == Parameter::Kind::Data)
        for (const auto& shape : scene.shapes)
            if (shape->group_shape == p.shape) out.push_back(shape.get());
    return out;
}

// A mesh with vertex normals whose vertex_positions were written gets them recomputed (Mitsuba 3's
// Mesh::parameters_changed); rigid motions rotate the normals instead.
void recompute_moved_normals(const Parameter& p) {
    if (p.kind == Parameter::Kind::Data && p.geometry && p.shape && !p.shape->face_normals &&
        !p.shape->mesh.normals.empty())
        recompute_vertex_normals(p.shape->mesh);
}

// Copies of moved group shapes follow their group shape's (new) vertices (finalize() follows).
void update_moved(const std::set<Shape*>& moved) {
    for (Shape* shape : moved)
        if (shape->group_shape && moved.count(const_cast<Shape*>(shape->group_shape)))
            shape->update_from_group();
}

// Rodrigues rotation of v about the unit axis a by angle t.
Vec3f rotate(const Vec3f& v, const Vec3f& a, float t) {
    const float c = std::cos(t), s = std::sin(t);
    return v * c + cross(a, v) * s + a * (dot(a, v) * (1.f - c));
}

// x -> x + θ d φ(x) (exact: X is linear in θ); normals by the inverse transpose of the deformation gradient
// F = I + θ d ∇φᵀ (Sherman–Morrison: F⁻ᵀ n = n - θ ∇φ (d·n) / (1 + θ ∇φ·d)).
void deform(TriangleMesh& mesh, const Motion& m, float theta) {
    for (size_t v = 0; v < mesh.positions.size(); ++v) {
        const Vec3f x = mesh.positions[v];
        mesh.positions[v] = x + m.vector * (theta * deform_weight(m, x));
        if (v >= mesh.normals.size()) continue;
        const Vec3f g = deform_weight_gradient(m, x);
        const Vec3f n = mesh.normals[v];
        mesh.normals[v] = normalize(n - g * (theta * dot(m.vector, n) / (1.f + theta * dot(g, m.vector))));
    }
}

} // namespace

Vec3f bbox_center(const std::vector<Shape*>& shapes) {
    Vec3f lo(Infinity), hi(-Infinity);
    for (const Shape* shape : shapes)
        for (const Vec3f& p : shape->mesh.positions) {
            lo = min(lo, p);
            hi = max(hi, p);
        }
    return (lo + hi) * 0.5f;
}

float bbox_diagonal(const std::vector<Shape*>& shapes) {
    Vec3f lo(Infinity), hi(-Infinity);
    for (const Shape* shape : shapes)
        for (const Vec3f& p : shape->mesh.positions) {
            lo = min(lo, p);
            hi = max(hi, p);
        }
    return norm(hi - lo);
}

Parameters::Parameters(Scene& scene) {
    // The estimators read world-space meshes (scene.shapes).
    scene.flatten_instances();
    // Boundary tests, auxiliary rays and edge samples meet triangle edges, where Embree's default test may let
    // a ray through: the derivative estimators (and the renders compared with them) trace with the watertight
    // test whatever the scene's embree_use_robust_intersections (WasDemo.OptimCorkscrew...: +90° ends at 3.5°
    // without it, 2.6° with it).
    if (!scene.robust_intersections) {
        scene.robust_intersections = true;
        scene.build();
    }
    std::set<const Object*> seen;
    Collector root(all_, seen, "", nullptr);
    // Objects with ids first, so that shared objects are named by their id wherever they are used.
    for (const auto& [id, object] : scene.named_objects)
        if (object->id == id) root.visit(object.get(), id);
    for (size_t i = 0; i < scene.shapes.size(); ++i) root.visit(scene.shapes[i].get(), shape_name(*scene.shapes[i], i));
    for (size_t i = 0; i < scene.emitters.size(); ++i) root.visit(scene.emitters[i].get(), "emitter_" + std::to_string(i));
    add_motions(scene);
    saved_sensor_ = scene.sensor->to_world;
}

Parameters::~Parameters() { disable_all(); }

void Parameters::add_motions(Scene& scene) {
    using Kind = Parameter::Kind;
    // `<owner>.translate`, `.rotate`, `.scale` (those of `kinds`), each moving what `moves` says.
    const auto add = [&](const std::string& owner, std::initializer_list<Kind> kinds,
                         const Parameter& moves) {
        for (Kind kind : kinds) {
            Parameter p = moves;
            p.name = owner + (kind == Kind::Translate ? ".translate"
                              : kind == Kind::Rotate  ? ".rotate"
                              : kind == Kind::Scale   ? ".scale"
                                                      : ".deform");
            p.kind = kind;
            all_.push_back(p);
        }
    };
    for (size_t i = 0; i < scene.shapes.size(); ++i) {
        Parameter moves;
        moves.geometry = true;
        moves.shape = scene.shapes[i].get();
        add(shape_name(*moves.shape, i), {Kind::Translate, Kind::Rotate, Kind::Scale, Kind::Deform}, moves);
    }
    // An instance of a group with several shapes: its motions move all its copies.
    for (const auto& [id, copies] : scene.instance_shapes) {
        if (copies.size() < 2) continue;
        Parameter moves;
        moves.geometry = true;
        moves.shape = copies[0];
        moves.shapes = copies;
        add(id, {Kind::Translate, Kind::Rotate, Kind::Scale, Kind::Deform}, moves);
    }
    Parameter camera;
    camera.sensor = true;
    add(scene.sensor->id.empty() ? "sensor" : scene.sensor->id, {Kind::Translate, Kind::Rotate}, camera);
    // Lights with a placement: point, spot and projector lights translate and rotate about their position;
    // directional lights and envmaps rotate.
    for (size_t i = 0; i < scene.emitters.size(); ++i) {
        Parameter light;
        light.emitter = scene.emitters[i].get();
        if (!light.emitter->movable()) continue;
        const std::string owner =
            light.emitter->id.empty() ? "emitter_" + std::to_string(i) : light.emitter->id;
        if (light.emitter->is_infinite())
            add(owner, {Kind::Rotate}, light);
        else
            add(owner, {Kind::Translate, Kind::Rotate}, light);
    }
}

const Parameter& Parameters::find(const std::string& name) const {
    for (const Parameter& p : all_)
        if (p.name == name) return p;
    // Mitsuba names a constant's value `<owner>.<param>.value`; the shorter `<owner>.<param>` is an alias.
    for (const Parameter& p : all_)
        if (p.name == name + ".value") return p;
    std::vector<std::pair<size_t, std::string>> close;
    for (const Parameter& p : all_) close.emplace_back(edit_distance(name, p.name), p.name);
    std::sort(close.begin(), close.end());
    std::string hint;
    for (size_t i = 0; i < std::min<size_t>(3, close.size()); ++i) hint += (i ? ", " : "") + close[i].second;
    throw Error("unknown parameter '" + name + "'" + (hint.empty() ? "" : " (did you mean: " + hint + "?)") +
                "; `penumbra params` lists them");
}

void Parameters::disable_all() {
    for (auto& [p, index] : enabled_)
        if (p->index) *p->index = -1;
    enabled_.clear();
    direction_.clear();
    dimension_ = tape_dimension_ = 0;
    for (Shape* shape : normal_leaf_shapes_) shape->vertex_normal_param_index = -1;
    normal_leaf_shapes_.clear();
    shape_motions_.clear();
    sensor_motions_.clear();
    emitter_motions_.clear();
}

void Parameters::enable(const std::vector<std::pair<std::string, std::vector<float>>>& selection) {
    disable_all();
    std::set<std::string> names;
    for (const auto& [selected, dir] : selection) {
        const auto [name, center] = split_motion_center(selected);
        const Parameter& p = find(name);
        if (center && (p.sensor || p.emitter ||
                       (p.kind != Parameter::Kind::Rotate && p.kind != Parameter::Kind::Scale &&
                        p.kind != Parameter::Kind::Deform)))
            throw Error("parameter '" + selected +
                        "': a center (@x,y,z) applies to the rotate, scale and deform motions of shapes");
        // A motion may be selected several times (e.g. the three axes of a translation), each with its own θ.
        if (p.kind == Parameter::Kind::Data && !names.insert(p.name).second)
            throw Error("parameter '" + name + "' is selected twice");
        const int index = dimension_;
        enabled_.emplace_back(&p, index);
        dimension_ += p.size;
        if (p.kind == Parameter::Kind::Data) {
            *p.index = index;
            if (dir.empty()) direction_.insert(direction_.end(), p.size, 1.f);
            else if (int(dir.size()) == p.size) direction_.insert(direction_.end(), dir.begin(), dir.end());
            else if (dir.size() == 1) direction_.insert(direction_.end(), p.size, dir[0]);
            else if (dir.size() == 3 && p.size % 3 == 0)
                for (int k = 0; k < p.size; ++k) direction_.push_back(dir[k % 3]);
            else
                throw Error("parameter '" + name + "' has " + std::to_string(p.size) + " values; its direction needs " +
                            std::to_string(p.size) + ", 3 (per 3-vector) or 1 value(s), got " + std::to_string(dir.size()));
            continue;
        }
        // Motions: θ is a scalar; the vector says which way.
        direction_.push_back(1.f);
        Motion m{p.kind, Vec3f(0.f), Vec3f(0.f), index};
        if (p.kind != Parameter::Kind::Scale) {
            if (dir.empty()) m.vector = p.kind == Parameter::Kind::Rotate ? Vec3f(0, 1, 0) : Vec3f(1, 0, 0);
            else if (dir.size() == 3) m.vector = Vec3f(dir[0], dir[1], dir[2]);
            else throw Error("motion '" + name + "' takes a 3-vector (e.g. " + name + "=0,1,0)");
            if (p.kind == Parameter::Kind::Rotate) {
                if (squared_norm(m.vector) == 0.f) throw Error("motion '" + name + "': the rotation axis is zero");
                m.vector = normalize(m.vector);
            }
        } else if (!dir.empty()) {
            throw Error("motion '" + name + "' (uniform scaling) takes no direction");
        }
        if (p.sensor) {
            sensor_motions_.push_back(m);
        } else if (p.emitter) {
            m.center = p.emitter->to_world().apply_point(Vec3f(0.f));
            emitter_motions_[p.emitter].push_back(m);
        } else {
            const std::vector<Shape*> shapes = motion_shapes(p);
            m.center = center ? *center : bbox_center(shapes);
            if (p.kind == Parameter::Kind::Deform) {
                m.radius = 0.25f * bbox_diagonal(shapes);
                if (!(m.radius > 0.f)) throw Error("motion '" + name + "': the shape has an empty bounding box");
            }
            for (Shape* shape : shapes)
                shape_motions_[shape].push_back(m);
        }
    }
    tape_dimension_ = dimension_;
    for (const auto& [p, index] : enabled_)
        if (p->kind == Parameter::Kind::Data && p->geometry && p->shape && !p->shape->flat_shading()) {
            p->shape->vertex_normal_param_index = tape_dimension_;
            tape_dimension_ += p->size;
            normal_leaf_shapes_.push_back(p->shape);
        }
}

void Parameters::enable_all_data() {
    std::vector<std::pair<std::string, std::vector<float>>> selection;
    for (const Parameter& p : all_)
        if (p.kind == Parameter::Kind::Data) selection.emplace_back(p.name, std::vector<float>{});
    enable(selection);
}

const std::vector<Motion>& Parameters::motions(const Shape* shape) const {
    static const std::vector<Motion> none;
    auto it = shape_motions_.find(shape);
    return it == shape_motions_.end() ? none : it->second;
}

const std::vector<Motion>& Parameters::emitter_motions(const Emitter* emitter) const {
    static const std::vector<Motion> none;
    auto it = emitter_motions_.find(emitter);
    return it == emitter_motions_.end() ? none : it->second;
}

void Parameters::displace(Scene& scene, double t) {
    // 1. Remember the reference configuration of everything that will move, and restore it.
    std::set<Shape*> moved;
    for (const auto& [p, index] : enabled_) {
        if (p->kind == Parameter::Kind::Data) {
            saved_data_.try_emplace(p->data, p->data, p->data + p->size);
            data_owners_.try_emplace(p->data, p->owner);
        }
        for (Shape* shape : moved_shapes(*p, scene))
            moved.insert(shape);
    }
    for (Shape* shape : moved) saved_meshes_.try_emplace(shape, shape->mesh.positions, shape->mesh.normals);
    for (auto& [data, values] : saved_data_) std::copy(values.begin(), values.end(), data);
    for (auto& [shape, mesh] : saved_meshes_) {
        std::copy(mesh.first.begin(), mesh.first.end(), shape->mesh.positions.begin());
        std::copy(mesh.second.begin(), mesh.second.end(), shape->mesh.normals.begin());
    }
    // 2. Data parameters move linearly along their direction.
    for (const auto& [p, index] : enabled_)
        if (p->kind == Parameter::Kind::Data) {
            for (int k = 0; k < p->size; ++k) p->data[k] += float(t * direction_[index + k]);
            recompute_moved_normals(*p);
        }
    for (const auto& [data, owner] : data_owners_)
        if (owner) owner->parameters_changed();
    update_moved(moved);
    // 3. Motions, exactly (finite θ = t), on top.
    const float theta = float(t);
    for (Shape* shape : moved) {
        for (const Motion& m : motions(shape)) {
            if (m.kind == Parameter::Kind::Deform) {
                deform(shape->mesh, m, theta);
                continue;
            }
            for (Vec3f& x : shape->mesh.positions) {
                if (m.kind == Parameter::Kind::Translate) x += m.vector * theta;
                else if (m.kind == Parameter::Kind::Rotate) x = m.center + rotate(x - m.center, m.vector, theta);
                else x = m.center + (x - m.center) * (1.f + theta);
            }
            if (m.kind == Parameter::Kind::Rotate)
                for (Vec3f& n : shape->mesh.normals) n = rotate(n, m.vector, theta);
        }
        shape->finalize();
    }
    Transform to_world = saved_sensor_;
    const Vec3f origin = saved_sensor_.apply_point(Vec3f(0.f));
    for (const Motion& m : sensor_motions_) {
        if (m.kind == Parameter::Kind::Translate)
            to_world = Transform::translate(m.vector * theta) * to_world;
        else
            to_world = Transform::translate(origin) * Transform::rotate(m.vector, degrees(theta)) *
                       Transform::translate(-origin) * to_world;
    }
    if (!sensor_motions_.empty() || !(scene.sensor->to_world.matrix == to_world.matrix))
        scene.sensor->set_transform(to_world);
    for (const auto& [p, index] : enabled_)
        if (p->emitter) saved_emitters_.try_emplace(p->emitter, p->emitter->to_world());
    for (auto& [emitter, reference] : saved_emitters_) {
        Transform placed = reference;
        for (const Motion& m : emitter_motions(emitter))
            placed = (m.kind == Parameter::Kind::Translate
                          ? Transform::translate(m.vector * theta)
                          : Transform::translate(m.center) * Transform::rotate(m.vector, degrees(theta)) *
                                Transform::translate(-m.center)) *
                     placed;
        emitter->set_to_world(placed);
    }
    if (!moved.empty()) scene.build();
}

void Parameters::set_direction(const std::vector<float>& direction) {
    if (direction.size() != size_t(dimension_))
        throw Error("set_direction: expected " + std::to_string(dimension_) + " values, got " +
                    std::to_string(direction.size()));
    direction_ = direction;
}

void Parameters::rebase(const Scene& scene) {
    saved_data_.clear();
    data_owners_.clear();
    saved_meshes_.clear();
    saved_emitters_.clear();
    saved_sensor_ = scene.sensor->to_world;
}

std::vector<float> Parameters::values() const {
    std::vector<float> v(size_t(dimension_), 0.f);
    for (const auto& [p, index] : enabled_)
        if (p->kind == Parameter::Kind::Data) std::copy(p->data, p->data + p->size, v.begin() + index);
    return v;
}

void Parameters::set_values(Scene& scene, const std::vector<float>& values, bool rebuild) {
    if (values.size() != size_t(dimension_))
        throw Error("set_values: expected " + std::to_string(dimension_) + " values, got " + std::to_string(values.size()));
    std::set<Shape*> moved;
    for (const auto& [p, index] : enabled_) {
        if (p->kind != Parameter::Kind::Data) throw Error("set_values: '" + p->name + "' is a motion; use displace()");
        for (int k = 0; k < p->size; ++k)
            if (!std::isfinite(values[index + k])) throw Error("set_values: non-finite value for '" + p->name + "'");
        std::copy(values.begin() + index, values.begin() + index + p->size, p->data);
        recompute_moved_normals(*p);
        if (p->owner) p->owner->parameters_changed();
        for (Shape* shape : moved_shapes(*p, scene))
            moved.insert(shape);
    }
    update_moved(moved);
    for (Shape* shape : moved) shape->finalize();
    if (!moved.empty() && rebuild) scene.build();
    saved_data_.clear(); // the new values are the reference configuration from now on
    data_owners_.clear();
    saved_meshes_.clear();
}

namespace {

// A comma-separated list of finite numbers; `context` names the option in errors.
std::vector<float> parse_numbers(const std::string& text, const std::string& context) {
    std::vector<float> out;
    std::stringstream list(text);
    std::string item;
    while (std::getline(list, item, ',')) {
        size_t used = 0;
        float v = 0.f;
        try {
            v = std::stof(item, &used);
        } catch (const std::exception&) {
            used = 0;
        }
        if (used == 0 || item.find_first_not_of(" \t", used) != std::string::npos || !std::isfinite(v))
            throw Error(context + ": '" + item + "' is not a finite number");
        out.push_back(v);
    }
    return out;
}

} // namespace

std::pair<std::string, std::vector<float>> parse_param_selection(const std::string& text) {
    const size_t eq = text.find('=');
    std::pair<std::string, std::vector<float>> result{text.substr(0, eq), {}};
    if (eq != std::string::npos) result.second = parse_numbers(text.substr(eq + 1), "--param " + text);
    return result;
}

std::pair<std::string, std::optional<Vec3f>> split_motion_center(const std::string& name) {
    const size_t at = name.find('@');
    if (at == std::string::npos) return {name, std::nullopt};
    const std::vector<float> c = parse_numbers(name.substr(at + 1), "parameter '" + name + "'");
    if (c.size() != 3)
        throw Error("parameter '" + name + "': the center after '@' takes 3 numbers (e.g. @0,0,0)");
    return {name.substr(0, at), Vec3f(c[0], c[1], c[2])};
}

} // namespace penumbra
