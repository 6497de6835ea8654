// Mitsuba 3 `mesh_attribute` texture: a per-vertex or per-face attribute of the mesh that was hit.
//
// Parameters:
//   name   string  (required)  "vertex_<attr>" or "face_<attr>": an attribute of the mesh (PLY properties
//   other
//                              than positions, normals and uvs, grouped as scene/mesh_ply.cpp describes)
//   scale  float   1           factor applied to the value
//
// Vertex attributes are interpolated barycentrically, (1 - b1 - b2) a0 + b1 a1 + b2 a2; face attributes are
// constant over each triangle. 1D attributes are broadcast to all three channels; 3D ones are RGB. The value
// is a constant of the surface point (its derivative with respect to a moving hit point is not tracked).
#include "scene/shape.h"
#include "scene/textures/textures.h"

namespace penumbra {

namespace {

class MeshAttributeTexture final : public TextureBase<MeshAttributeTexture> {
  public:
    MeshAttributeTexture(std::string name, float scale) : name_(std::move(name)), scale_(scale) {
        vertex_ = name_.rfind("vertex_", 0) == 0;
    }

    template <typename T> Color3<T> eval_t(const SurfaceInteraction<T>& si) const {
        if (!si.shape) return Color3<T>(T(0.f));
        const TriangleMesh& mesh = si.shape->mesh;
        const MeshAttribute* a = mesh.attribute(name_);
        if (!a || (a->dim != 1 && a->dim != 3))
            throw Error("mesh_attribute: shape " + si.shape->to_string() +
                        (a ? " has attribute '" + name_ + "' of dimension " + std::to_string(a->dim) +
                                 " (1 or 3 expected)"
                           : " has no attribute '" + name_ + "'"));
        auto value = [&](size_t element) {
            const float* v = &a->values[element * size_t(a->dim)];
            return a->dim == 1 ? Color3f(v[0]) : Color3f(v[0], v[1], v[2]);
        };
        Color3f c;
        if (vertex_) {
            const uint32_t* i = &mesh.indices[3 * size_t(si.prim_index)];
            const float b1 = si.bary.x, b2 = si.bary.y;
            c = value(i[0]) * (1.f - b1 - b2) + value(i[1]) * b1 + value(i[2]) * b2;
        } else {
            c = value(si.prim_index);
        }
        return Color3<T>(c * scale_);
    }

    // The mean over the domain needs the mesh, which a texture does not know: mid-grey times the scale (only
    // a lobe-selection heuristic of the plastic BSDFs uses it).
    Color3f mean() const override { return Color3f(scale_ * 0.5f); }
    std::string to_string() const override { return "MeshAttributeTexture[" + name_ + "]"; }

  private:
    std::string name_;
    float scale_;
    bool vertex_ = true;
};

} // namespace

std::shared_ptr<Texture> make_mesh_attribute_texture(const Properties& props) {
    const std::string name = props.get_string("name");
    if (name.rfind("vertex_", 0) != 0 && name.rfind("face_", 0) != 0)
        props.raise("name",
                    "invalid mesh attribute name '" + name + "' (must start with 'vertex_' or 'face_')");
    return std::make_shared<MeshAttributeTexture>(name, props.get_float("scale", 1.f));
}

} // namespace penumbra
