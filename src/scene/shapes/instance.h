// shapegroup and instance (Mitsuba 3): shapes declared once in a group, placed any number of times by
// instances with their own to_world. The group's meshes stay in group space and are stored once; Embree
// traces them through one shared BVH per group (scene.cpp).
#pragma once
#include "scene/properties.h"
#include "scene/shape.h"

#include <memory>
#include <vector>

namespace penumbra {

class ShapeGroup : public Object {
  public:
    ObjectKind kind() const override { return ObjectKind::Shape; }
    std::string to_string() const override;
    // Each shape, named by its id or `<group id>.<index>` (their vertex_positions move every instance).
    void traverse(ParamVisitor& v) override;
    std::vector<std::shared_ptr<Shape>> shapes; // group space
    size_t triangle_count() const;
};

class Instance : public Object {
  public:
    ObjectKind kind() const override { return ObjectKind::Shape; }
    std::string to_string() const override;
    std::shared_ptr<ShapeGroup> group;
    Transform to_world;

    // The interaction at a hit of group shape `shape` (primitive prim, barycentrics b1, b2) found by the
    // world ray at distance t: computed in group space, then moved to world space (points and tangents by
    // to_world, normals by its inverse transpose, as Mitsuba's instance).
    SurfaceInteraction3f compute_surface_interaction(const Ray& ray, float t, const Shape& shape,
                                                     uint32_t prim, float b1, float b2) const;
};

std::shared_ptr<Object> make_shapegroup(const Properties& props);
std::shared_ptr<Object> make_instance(const Properties& props);

} // namespace penumbra
