// make_shape: Mitsuba 3 shape plugins, all turned into world-space triangle meshes.
//
//  plugin      parameter        type       default
//  obj         filename         string     (required)
//              face_normals     bool       false
//              flip_tex_coords  bool       true    (uv.y = 1 - uv.y)
//  ply         filename         string     (required)
//              face_normals     bool       false
//  serialized  filename         string     (required)
//              shape_index      int        0
//              face_normals     bool       false
//  cube        face_normals     bool       false
//  sphere      center           point      (0, 0, 0)
//              radius           float      1
//  cylinder    p0, p1, radius   (shapes/cylinder.cpp)
//  shapegroup, instance         (shapes/instance.cpp)
//  linearcurve, bsplinecurve    filename, silhouette_sampling_weight (shapes/linearcurve.cpp,
//                               bsplinecurve.cpp); to_world moves the control points, not the radii
//  all         to_world         transform  identity
//              flip_normals     bool       false
//              nested bsdf (at most one; default: diffuse), area emitter (at most one),
//              interior / exterior medium, sensor (irradiancemeter, at most one)
//
// Loaded meshes without vertex normals get smooth ones (Mitsuba 3 recomputes them unless face_normals is
// set). Primitives are tessellated: the sphere as 64 x 128 (theta x phi) quads, the disk as a 256-triangle
// fan.
#include "scene/factory.h"
#include "scene/medium.h"
#include "scene/sensor.h"
#include "scene/shape.h"
#include "scene/shapes/instance.h"
#include "scene/shapes/shapes.h"

namespace penumbra {
namespace {

constexpr int SphereRings = 64, SphereSegments = 128, DiskSegments = 256;

// flip_normals: reversed winding flips the geometric normal; vertex normals are negated to match.
void flip_orientation(TriangleMesh& mesh) {
    for (size_t f = 0; f < mesh.face_count(); ++f)
        std::swap(mesh.indices[3 * f + 1], mesh.indices[3 * f + 2]);
    for (Vec3f& n : mesh.normals)
        n = -n;
}

TriangleMesh load_mesh_file(const Properties& props, const LoadContext& ctx) {
    const std::string path = ctx.resolve(props.get_string("filename"), props.location("filename"));
    const std::string& type = props.plugin();
    try {
        if (type == "obj") {
            TriangleMesh mesh = load_obj(path);
            if (props.get_bool("flip_tex_coords", true))
                for (Vec2f& uv : mesh.uvs)
                    uv.y = 1.f - uv.y;
            return mesh;
        }
        if (type == "ply") return load_ply(path);
        const int64_t index = props.get_int("shape_index", 0);
        if (index < 0 || index > INT32_MAX) props.raise("shape_index", "must be a non-negative integer");
        return load_serialized(path, int(index));
    } catch (const LoadError&) {
        throw;
    } catch (const Error& e) {
        throw LoadError(props.location("filename"), e.what());
    }
}

template <typename T>
std::shared_ptr<T> at_most_one(const Properties& props, ObjectKind kind, const char* what) {
    const auto objects = props.objects(kind);
    if (objects.size() > 1)
        throw LoadError(objects[1]->location, "shape '" + props.plugin() + "' has more than one " + what);
    return objects.empty() ? nullptr : std::dynamic_pointer_cast<T>(objects[0]);
}

} // namespace

std::shared_ptr<Object> make_shape(const Properties& props, const LoadContext& ctx) {
    const std::string& type = props.plugin();
    if (type == "shapegroup") return make_shapegroup(props);
    if (type == "instance") return make_instance(props);
    const bool from_file = type == "obj" || type == "ply" || type == "serialized";
    if (type == "sdfgrid")
        throw LoadError(props.location(),
                        "unsupported shape plugin 'sdfgrid' (penumbra intersects triangle meshes "
                        "only; convert the signed distance field to a mesh, e.g. by marching cubes)");
    const bool curve = type == "linearcurve" || type == "bsplinecurve";
    if (!from_file && !curve && type != "rectangle" && type != "cube" && type != "disk" && type != "sphere" &&
        type != "cylinder")
        throw_unsupported_plugin(props, ObjectKind::Shape);

    auto shape = std::make_shared<Shape>();
    shape->plugin = type; // set early: finalize() names the shape in its errors
    shape->location = props.location();
    if (from_file) {
        shape->mesh = load_mesh_file(props, ctx);
    } else if (type == "rectangle") {
        shape->mesh = make_rectangle_mesh();
    } else if (type == "cube") {
        shape->mesh = make_cube_mesh();
    } else if (type == "disk") {
        shape->mesh = make_disk_mesh(DiskSegments);
    } else if (type == "cylinder") {
        shape->mesh = make_cylinder(props);
    } else if (type == "linearcurve") {
        shape->mesh = make_linearcurve(props, ctx);
    } else if (type == "bsplinecurve") {
        shape->mesh = make_bsplinecurve(props, ctx);
    } else {
        const float radius = props.get_float("radius", 1.f);
        if (!(radius > 0.f) || !std::isfinite(radius)) props.raise("radius", "must be positive");
        shape->mesh =
            make_sphere_mesh(props.get_vector("center", Vec3f(0.f)), radius, SphereRings, SphereSegments);
    }
    if (from_file || type == "cube") shape->face_normals = props.get_bool("face_normals", false);
    const bool flip_normals = props.get_bool("flip_normals", false);

    if (!curve) shape->mesh.apply_transform(props.get_transform("to_world"));
    if (shape->face_normals)
        shape->mesh.normals.clear();
    else if (from_file && shape->mesh.normals.empty())
        recompute_vertex_normals(shape->mesh);
    if (flip_normals) flip_orientation(shape->mesh);

    shape->bsdf = at_most_one<BSDF>(props, ObjectKind::BSDF, "BSDF");
    if (!shape->bsdf)
        shape->bsdf =
            std::dynamic_pointer_cast<BSDF>(make_bsdf(Properties("diffuse", props.location()), ctx));
    shape->emitter = at_most_one<Emitter>(props, ObjectKind::Emitter, "emitter");
    if (shape->emitter && !(shape->emitter->flags() & EmitterSurface))
        throw LoadError(shape->emitter->location,
                        "a shape can only carry an area emitter, not '" + shape->emitter->plugin + "'");
    if (shape->emitter && type == "linearcurve")
        throw LoadError(shape->emitter->location,
                        "a linearcurve cannot carry an area emitter (its tessellation "
                        "overlaps at the joints, which would count twice in its area)");
    shape->interior = std::dynamic_pointer_cast<Medium>(props.get_object("interior", ObjectKind::Medium));
    shape->exterior = std::dynamic_pointer_cast<Medium>(props.get_object("exterior", ObjectKind::Medium));

    shape->finalize();
    if (shape->emitter) shape->emitter->set_shape(shape.get());
    shape->sensor = at_most_one<Sensor>(props, ObjectKind::Sensor, "sensor");
    if (shape->sensor) shape->sensor->attach_to(*shape);
    return shape;
}

} // namespace penumbra
