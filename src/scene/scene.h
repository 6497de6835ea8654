// The scene: shapes in an Embree BVH, emitters, the sensor and the integrator description.
#pragma once
#include "scene/emitter.h"
#include "scene/integrator_settings.h"
#include "scene/medium.h"
#include "scene/sensor.h"
#include "scene/shape.h"
#include "scene/shapes/instance.h"

#include <map>
#include <memory>
#include <string>
#include <vector>

namespace penumbra {

class Scene {
public:
    Scene();
    ~Scene();
    Scene(const Scene&) = delete;
    Scene& operator=(const Scene&) = delete;

    std::vector<std::shared_ptr<Shape>> shapes;
    std::vector<std::shared_ptr<Instance>> instances; // placements of shapegroups (their meshes stored once)
    std::vector<std::shared_ptr<Emitter>> emitters; // all emitters, area emitters included
    std::shared_ptr<Sensor> sensor;                 // the sensor rendered: sensors[0] unless selected
    std::vector<std::shared_ptr<Sensor>> sensors; // every sensor, in declaration order (Mitsuba's sensors())
    // The <integrator>'s settings (default: path); render() makes the integrator object from them.
    std::shared_ptr<const IntegratorSettings> integrator;
    // Every object with an `id`, for parameter lookup and `info`.
    std::map<std::string, std::shared_ptr<Object>> named_objects;
    std::string source_path;
    // Embree's watertight (robust) triangle test: Mitsuba 3's scene parameter embree_use_robust_intersections,
    // off by default as there for rendering (about 9% faster on the Cornell box; a ray through a shared edge
    // may miss both triangles); Parameters turns it on (the derivative estimators). Takes effect at build().
    bool robust_intersections = false;

    // Makes `which` (an index into sensors, or a sensor's id) the rendered sensor; throws Error naming the
    // sensors otherwise.
    void select_sensor(const std::string& which);

    // Builds the BVH, emitter bookkeeping and scene bounds. Must be called after the lists are filled.
    void build();
    // Replaces every instance by world-space copies of its group's shapes (Shape::group_shape), named
    // `<instance id>` (one group shape) or `<instance id>.<group shape id or index>`, and rebuilds the BVH.
    // The derivative estimators read world-space meshes, so Parameters calls this: memory is then
    // O(instances × group triangles) while differentiating; rendering alone keeps instancing. Shared
    // geometry stays shared through the copies' group_shape (its vertex_positions moves them all).
    void flatten_instances();
    // After flatten_instances(): the copies of each instance that had an id, by that id.
    std::map<std::string, std::vector<Shape*>> instance_shapes;

    SurfaceInteraction3f intersect(const Ray& ray) const;
    bool occluded(const Ray& ray) const;
    BoundingSphere bounding_sphere() const { return bounds_; }

    // Uniform emitter selection, then the emitter's own sampling (Mitsuba 3's scheme). The weight includes the
    // selection probability; when test_visibility is set an occluded sample gets zero weight.
    std::pair<DirectionSample3f, Color3f> sample_emitter_direction(const Interaction3f& ref, const Vec2f& u,
                                                                  bool test_visibility) const;
    float pdf_emitter_direction(const Interaction3f& ref, const DirectionSample3f& ds) const;
    // Samples an emitter for light tracing; returns the emitter and sets `pdf` to its selection probability.
    const Emitter* sample_emitter(float& u, float& pdf) const;
    // The same as an index into `emitters` (the scene must have emitters).
    size_t sample_emitter_index(float& u, float& pdf) const;
    // Radiance from all infinite emitters along an escaped ray direction.
    Color3f eval_environment(const Vec3f& d) const;

    // Triangles stored: the shapes' and each instanced group's once.
    size_t triangle_count() const;
    // Triangles rendered: the shapes' and every instance's.
    size_t instanced_triangle_count() const;

private:
    struct EmbreeState;
    std::unique_ptr<EmbreeState> embree_;
    std::vector<const Emitter*> infinite_emitters_;
    BoundingSphere bounds_;
};

// Loads a Mitsuba 3 XML scene. `defines` override <default> values (like mitsuba's -D name=value).
std::unique_ptr<Scene> load_scene(const std::string& path, const std::map<std::string, std::string>& defines = {});
// Loads a scene from an XML string (relative paths resolve against `base_dir`).
std::unique_ptr<Scene> load_scene_string(const std::string& xml, const std::string& base_dir = ".",
                                         const std::map<std::string, std::string>& defines = {});

} // namespace penumbra
