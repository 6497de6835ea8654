// Differentiable scene parameters: discovery with Mitsuba 3 `traverse` names, geometric motions, and the
// selection of the parameters (and the direction in parameter space) that an estimator differentiates.
//
// Names: Mitsuba 3's traverse() keys. An object with an `id` is named by it; nested objects append the name
// their parent gives them (`plane.bsdf.reflectance.value`, `light.emitter.radiance.value`: a constant's value
// is `value`, and find() also accepts the name without it); objects without an id at the top level are named
// `<kind>_<n>` (e.g. `shape_2`). Shared objects are listed once, under their id.
// Motions (virtual scalar parameters θ with value 0 in the reference configuration, paper 001 §4.1):
//   <shape>.translate  x -> x + θ d             (d: a world-space vector)
//   <shape>.rotate     x -> c + R(a, θ)(x - c)  (a: world axis, θ in radians, c: the bounding-box center)
//   <shape>.scale      x -> c + (1 + θ)(x - c)  (uniform, about the bounding-box center)
//   <shape>.deform     x -> x + θ d φ(x), φ(x) = exp(-|x - c|² / (2 r²))   (a cage-free non-rigid deformation:
//                      d a world vector, c the bounding-box center, r a quarter of the bounding box's diagonal,
//                      so that φ falls to e^-2 at the box's corners and the shape bends rather than translates;
//                      several selections, each with its own d and center, are a pose of few control variables)
//   <shape>.rotate@cx,cy,cz, <shape>.scale@cx,cy,cz, <shape>.deform@cx,cy,cz: the same about the world point c
//                      (plane.scale@0,0,0 scales about the origin, as Mitsuba's tests do)
//   <sensor>.translate / <sensor>.rotate        the camera moves (world axes; rotation about its position)
//   <emitter>.translate / <emitter>.rotate      a point, spot or projector light moves (rotation about its
//                      position); <emitter>.rotate turns a directional light's direction or an envmap
// Instances (<shape type="instance">) are flattened into world-space shapes first (Scene::flatten_instances):
//   <instance id>.translate/rotate/scale/deform   all shapes of the instance together (center and radius:
//                      their bounding box)
//   <group shape>.vertex_positions         group-space positions (copies move by their to_world's linear map)
#pragma once
#include "scene/emitter.h"
#include "scene/scene.h"

#include <map>
#include <optional>
#include <string>
#include <vector>

namespace penumbra {

struct Parameter {
    enum class Kind { Data, Translate, Rotate, Scale, Deform };
    std::string name;
    Kind kind = Kind::Data;
    float* data = nullptr;  // Data: the values inside the scene object
    int size = 1;           // number of scalars
    std::vector<int> dims;  // Data: the array's shape ({H, W, 3} images, {N, 3} vertex positions, {3}, {1})
    int* index = nullptr;   // Data: where the object reads its parameter index (core/param.h)
    Object* owner = nullptr; // Data: the object that listed it (told by parameters_changed() when written)
    bool geometry = false;  // changing it moves geometry (the BVH must be rebuilt)
    Shape* shape = nullptr; // motions of shapes, and vertex_positions
    std::vector<Shape*> shapes; // motions of an instance of a group with several shapes: its flattened copies
    bool sensor = false;    // motions of the camera
    Emitter* emitter = nullptr; // motions of a light
};

// A motion in use: which parameter index drives it and how (first-order form at θ = 0).
struct Motion {
    Parameter::Kind kind;
    Vec3f vector; // translation or deformation direction, or rotation axis
    Vec3f center; // rotation / scaling / deformation center
    int index;    // parameter index of θ
    float radius = 0.f; // Deform: the radius r of φ
};

// φ(x) = exp(-|x - c|² / (2 r²)) of a Deform motion (x -> x + θ d φ(x)), and its gradient -φ (x - c) / r².
inline float deform_weight(const Motion& m, const Vec3f& x) {
    return std::exp(-squared_norm(x - m.center) / (2.f * m.radius * m.radius));
}
inline Vec3f deform_weight_gradient(const Motion& m, const Vec3f& x) {
    return (x - m.center) * (-deform_weight(m, x) / (m.radius * m.radius));
}

class Parameters {
public:
    explicit Parameters(Scene& scene);
    ~Parameters();
    Parameters(const Parameters&) = delete;
    Parameters& operator=(const Parameters&) = delete;

    const std::vector<Parameter>& all() const { return all_; }
    // Throws Error naming the closest known names if `name` is unknown.
    const Parameter& find(const std::string& name) const;

    // Enables parameters for differentiation, each with a direction: `direction` has the parameter's size, or
    // 3 values broadcast over an array of 3-vectors (colors, vertex positions), or 1 value broadcast; for
    // translate and deform it is the world vector, for rotate the world axis (empty: unit directions / +x for
    // translate and deform / +y axis).
    // Indices are assigned contiguously in the given order. A motion may be selected several times, each
    // selection with its own direction and scalar θ (a pose: translate along x, y, z and rotate about x, y, z);
    // a Data parameter only once. Disables everything enabled before.
    void enable(const std::vector<std::pair<std::string, std::vector<float>>>& selection);
    // Reverse mode: every Data parameter, with no direction.
    void enable_all_data();
    void disable_all();

    // Dimension of the enabled parameter vector, and the direction (forward mode) in it.
    int dimension() const { return dimension_; }
    // The tape's leaves: the parameters, then the recomputed vertex normals of the meshes whose vertex
    // positions are enabled and shaded with vertex normals (diff/vertex_normals.h). Forward and reverse sweeps
    // take vectors of this size.
    int tape_dimension() const { return tape_dimension_; }
    const std::vector<Shape*>& normal_leaf_shapes() const { return normal_leaf_shapes_; }
    const std::vector<float>& direction() const { return direction_; }
    // Replaces the direction (dimension() values): a motion's θ may then move at another rate than 1.
    void set_direction(const std::vector<float>& direction);
    // Enabled parameters with their first index.
    const std::vector<std::pair<const Parameter*, int>>& enabled() const { return enabled_; }

    // Motions driving a shape / the camera (empty when none is enabled).
    const std::vector<Motion>& motions(const Shape* shape) const;
    const std::vector<Motion>& sensor_motions() const { return sensor_motions_; }
    // Motions of a light (rotations about its position: Motion::center).
    const std::vector<Motion>& emitter_motions(const Emitter* emitter) const;
    // Whether the enabled parameters move the shape (a motion, or its vertex positions).
    bool moves(const Shape& shape) const { return !motions(&shape).empty() || shape.vertex_index() >= 0; }

    // Values of the enabled parameters (motions read 0: they are displacements from the reference).
    std::vector<float> values() const;
    // Writes values of the enabled Data parameters into the scene (rebuilding the BVH when geometry changed
    // and `rebuild`); throws Error on non-finite values or motions (use displace() for those).
    void set_values(Scene& scene, const std::vector<float>& values, bool rebuild = true);

    // Moves the scene to θ0 + t·direction (t = 0 restores the reference configuration) and rebuilds the BVH
    // when geometry moved. Used by finite differences.
    void displace(Scene& scene, double t);
    // The scene as it is now (moved from outside, e.g. by a ParameterTable) becomes the configuration that
    // displace(scene, 0) restores.
    void rebase(const Scene& scene);

  private:
    void add_motions(Scene& scene);
    std::vector<Parameter> all_;
    std::vector<std::pair<const Parameter*, int>> enabled_;
    std::vector<float> direction_;
    int dimension_ = 0, tape_dimension_ = 0;
    std::vector<Shape*> normal_leaf_shapes_;
    std::map<const Shape*, std::vector<Motion>> shape_motions_;
    std::vector<Motion> sensor_motions_;
    std::map<const Emitter*, std::vector<Motion>> emitter_motions_;
    // Reference values of everything displace() may change.
    std::map<float*, std::vector<float>> saved_data_;
    std::map<float*, Object*> data_owners_; // owners of the values in saved_data_
    std::map<Shape*, std::pair<std::vector<Vec3f>, std::vector<Vec3f>>> saved_meshes_;
    Transform saved_sensor_;
    std::map<Emitter*, Transform> saved_emitters_;
};

// The center of the bounding box of the shapes' meshes (the default center of their rotate, scale and deform
// motions).
Vec3f bbox_center(const std::vector<Shape*>& shapes);
// The length of the diagonal of that bounding box.
float bbox_diagonal(const std::vector<Shape*>& shapes);

// Parses "name" or "name=v1,v2,..." (the CLI's --param syntax).
std::pair<std::string, std::vector<float>> parse_param_selection(const std::string& text);
// Splits a selected name "name@cx,cy,cz" into the parameter's name and the motion's center (none without
// '@').
std::pair<std::string, std::optional<Vec3f>> split_motion_center(const std::string& name);

} // namespace penumbra
