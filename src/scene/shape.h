// Shapes: a triangle mesh in world space with its material, optional area emitter and media.
#pragma once
#include "core/distribution.h"
#include "scene/bsdf.h"
#include "scene/emitter.h"
#include "scene/interaction.h"
#include "scene/mesh.h"

#include <memory>
#include <utility>

namespace penumbra {

class Medium;
class Sensor;

// What a hit takes from its triangle alone: the geometric normal n and, when the shading frame is the same
// over the triangle (flat shading, or three equal vertex normals), that frame; otherwise s = dp/du
// (Gram-Schmidt against the interpolated normal per hit). 48 bytes per triangle.
struct TriangleShading {
    Vec3f n;
    Frame3f frame;
    bool constant_frame() const { return frame.n.x == frame.n.x; } // NaN n: varies over the triangle
};

class Shape : public Object {
public:
    ObjectKind kind() const override { return ObjectKind::Shape; }
    std::string to_string() const override;

    TriangleMesh mesh; // world space
    std::shared_ptr<BSDF> bsdf;
    std::shared_ptr<Emitter> emitter; // area emitter, or null
    std::shared_ptr<Medium> interior, exterior;
    std::shared_ptr<Sensor> sensor;   // a nested sensor measuring the shape (irradiancemeter), or null
    bool face_normals = false;        // ignore per-vertex normals (finalize() must follow a change)
    int vertex_param_index = -1;      // first parameter index of vertex_positions when differentiated
    int vertex_normal_param_index = -1; // first tape leaf index of its recomputed vertex normals when its
                                        // vertex_positions are differentiated (diff/vertex_normals.h)
    // A world-space copy of a shapegroup's shape made by Scene::flatten_instances(): the group shape and the
    // instance's to_world. Its vertices are the group shape's `vertex_positions` moved by that transform.
    const Shape* group_shape = nullptr;
    Transform instance_to_world;

    // First parameter index of the vertex positions that move this mesh: its own, or its group shape's.
    int vertex_index() const { return group_shape ? group_shape->vertex_param_index : vertex_param_index; }
    // First tape leaf index of the recomputed vertex normals of this mesh (its group shape's), or -1.
    int vertex_normal_index() const {
        return group_shape ? group_shape->vertex_normal_param_index : vertex_normal_param_index;
    }
    // A flattened copy: the mesh recomputed from the group shape's (positions by to_world, normals by its
    // inverse transpose, as TriangleMesh::apply_transform); finalize() must follow.
    void update_from_group();

    // `vertex_positions` (geometry; not for flattened copies, whose vertices are their group shape's), and
    // the nested bsdf and emitter.
    void traverse(ParamVisitor& v) override;

    // Validates the mesh and builds the area distribution. Degenerate (zero-area) triangles are kept in the
    // mesh but never sampled; `degenerate_count` reports them. A mesh with zero total area is an error.
    void finalize();
    float surface_area() const { return total_area_; }
    size_t degenerate_count() const { return degenerate_count_; }

    // The faces around vertex v, [first, last): the terms of its smooth normal (recompute_vertex_normals).
    // Built by finalize() for meshes shaded with vertex normals.
    std::pair<const uint32_t*, const uint32_t*> faces_around(uint32_t v) const {
        return {ring_faces_.data() + ring_offsets_[v], ring_faces_.data() + ring_offsets_[v + 1]};
    }

    // Uniform sampling by area (pdf = 1 / area).
    PositionSample3f sample_position(const Vec2f& u) const;
    float pdf_position() const { return 1.f / total_area_; }

    // Geometric normal of a triangle (unit, from the winding order).
    Vec3f face_normal(uint32_t prim) const;
    // Shading normal = geometric normal (no vertex normals, or face_normals).
    bool flat_shading() const { return face_normals || mesh.normals.empty(); }
    // What surface_interaction() takes from a triangle alone, kept by finalize() (null before).
    const TriangleShading* triangle_shading(uint32_t prim) const {
        return triangles_.empty() ? nullptr : &triangles_[prim];
    }
    // Fills a surface interaction from a ray hit at distance t in triangle prim with barycentrics (b1, b2).
    SurfaceInteraction3f compute_surface_interaction(const Ray& ray, float t, uint32_t prim, float b1, float b2) const;

private:
    void build_rings();
    void build_triangle_shading();
    DiscreteDistribution area_distribution_;
    std::vector<TriangleShading> triangles_;
    std::vector<uint32_t> ring_offsets_, ring_faces_;
    float total_area_ = 0.f;
    size_t degenerate_count_ = 0;
};

template <typename T> const BSDF* SurfaceInteraction<T>::bsdf() const { return shape ? shape->bsdf.get() : nullptr; }
template <typename T> const Emitter* SurfaceInteraction<T>::emitter() const {
    return shape ? shape->emitter.get() : nullptr;
}

} // namespace penumbra
