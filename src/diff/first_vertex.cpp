#include "diff/first_vertex.h"

#include "scene/texture.h"

namespace penumbra {

FirstVertex parse_first_vertex(const std::string& name) {
    if (name == "auto") return FirstVertex::Auto;
    if (name == "image") return FirstVertex::ImageSpace;
    if (name == "material") return FirstVertex::Material;
    throw Error("unknown first-vertex form '" + name + "' (expected auto, image or material)");
}

namespace {

// Walks an object's nested objects (BSDFs, textures, emitters) looking for a texture that jumps in uv.
class DiscontinuousTextureFinder final : public ParamVisitor {
public:
    void put(const std::string&, float*, int, int*, bool) override {}
    void put_object(const std::string&, Object* object) override {
        if (!object || found) return;
        if (const auto* texture = dynamic_cast<const Texture*>(object); texture && !texture->is_continuous()) found = true;
        object->traverse(*this);
    }
    bool found = false;
};

bool moves(const Shape& shape, const Parameters& params) {
    return !params.motions(&shape).empty() || shape.vertex_param_index >= 0;
}

} // namespace

bool image_space_first_vertex(const Scene& scene, const Parameters& params, FirstVertex choice) {
    const bool camera_moves = !params.sensor_motions().empty();
    if (choice == FirstVertex::ImageSpace && camera_moves)
        throw Error("the image-space first vertex needs a static camera: the sensor moves (use --first-vertex material)");
    if (choice != FirstVertex::Auto) return choice == FirstVertex::ImageSpace;
    if (camera_moves) return false;
    for (const auto& shape : scene.shapes) {
        if (!moves(*shape, params)) continue;
        DiscontinuousTextureFinder finder;
        shape->traverse(finder);
        if (finder.found) return false;
    }
    return true;
}

} // namespace penumbra
