// shapegroup / instance: Mitsuba 3's instancing.
//
//  plugin      parameter  type       default
//  shapegroup  (nested shapes)       shapes of any plugin except shapegroup and instance, without emitters
//                                    (Mitsuba 3: "instancing of emitters is not supported")
//  instance    to_world   transform  identity
//              (one nested or referenced shapegroup, required)
//
// A shapegroup is a declaration: it renders only through instances. To differentiate, Parameters flattens
// the instances into world-space shapes (Scene::flatten_instances): `<instance id>.translate/rotate/scale`
// move one instance, `<group shape>.vertex_positions` (group space) moves every instance of the group shape.
#include "scene/shapes/instance.h"

#include "scene/factory.h"
#include "scene/shape_interaction.h"

#include <sstream>

namespace penumbra {

size_t ShapeGroup::triangle_count() const {
    size_t n = 0;
    for (const auto& s : shapes)
        n += s->mesh.face_count();
    return n;
}

void ShapeGroup::traverse(ParamVisitor& v) {
    for (size_t k = 0; k < shapes.size(); ++k)
        v.put_object(std::to_string(k), shapes[k].get());
}

std::string ShapeGroup::to_string() const {
    std::ostringstream os;
    os << "ShapeGroup[shapes=" << shapes.size() << ", triangles=" << triangle_count() << "]";
    return os.str();
}

std::string Instance::to_string() const {
    std::ostringstream os;
    os << "Instance[group=" << (group->id.empty() ? "(unnamed)" : group->id)
       << ", to_world=" << to_world.to_string() << "]";
    return os.str();
}

std::shared_ptr<Object> make_shapegroup(const Properties& props) {
    auto group = std::make_shared<ShapeGroup>();
    for (const auto& object : props.objects(ObjectKind::Shape)) {
        auto shape = std::dynamic_pointer_cast<Shape>(object);
        if (!shape)
            throw LoadError(object->location, "a shapegroup cannot contain a '" + object->plugin +
                                                  "' (nested instancing is not supported, as in Mitsuba 3)");
        if (shape->emitter)
            throw LoadError(object->location,
                            "a shape inside a shapegroup cannot carry an emitter (instancing of "
                            "emitters is not supported, as in Mitsuba 3)");
        group->shapes.push_back(std::move(shape));
    }
    if (group->shapes.empty()) throw LoadError(props.location(), "a shapegroup needs at least one shape");
    return group;
}

std::shared_ptr<Object> make_instance(const Properties& props) {
    auto instance = std::make_shared<Instance>();
    const auto objects = props.objects(ObjectKind::Shape);
    for (const auto& object : objects) {
        auto group = std::dynamic_pointer_cast<ShapeGroup>(object);
        if (!group)
            throw LoadError(object->location,
                            "an instance references a shapegroup, not a '" + object->plugin + "'");
        if (instance->group)
            throw LoadError(object->location,
                            "an instance references exactly one shapegroup (this is a second)");
        instance->group = std::move(group);
    }
    if (!instance->group)
        throw LoadError(props.location(), "an instance needs a shapegroup (nest it or <ref> it)");
    instance->to_world = props.get_transform("to_world");
    return instance;
}

namespace {

// Vertex data of a group's mesh seen through an instance: as the mesh would be stored after
// TriangleMesh::apply_transform(to_world).
struct InstanceVertices {
    const TriangleMesh& mesh;
    const Transform& to_world;
    Vec3f position(uint32_t v) const { return to_world.apply_point(mesh.positions[v]); }
    Vec3f normal(uint32_t v) const {
        const Vec3f n = to_world.apply_normal(mesh.normals[v]);
        const float length = norm(n);
        return length > 0.f ? n / length : n;
    }
};

} // namespace

// The mesh interaction of shape_interaction.h on the triangle's vertices moved to world space: the same code
// and result as for the flattened shape. Barycentrics are invariant under the affine to_world.
SurfaceInteraction3f Instance::compute_surface_interaction(const Ray& ray, float t, const Shape& shape,
                                                           uint32_t prim, float b1, float b2) const {
    SurfaceInteraction3f si =
        surface_interaction<float>(shape, prim, Vec2f(b1, b2), InstanceVertices{shape.mesh, to_world});
    si.t = t;
    si.wi = si.to_local(-ray.d);
    return si;
}

} // namespace penumbra
