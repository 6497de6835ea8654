#include "diff/first_vertex.h"

#include "scene/texture.h"

namespace penumbra {

FirstVertex parse_first_vertex(const std::string& name) {
    if (name == "auto") return FirstVertex::Auto;
    if (name == "image") return FirstVertex::ImageSpace;
    if (name == "material") return FirstVertex::Material;
    throw Error("unknown first-vertex form '" + name + "' (expected auto, image or material)");
}

bool image_space_first_vertex(const Scene& scene, const Parameters& params, FirstVertex choice) {
    const bool camera_moves = !params.sensor_motions().empty();
    if (choice == FirstVertex::ImageSpace && camera_moves)
        throw Error("the image-space first vertex needs a static camera: the sensor moves (use --first-vertex material)");
    if (choice != FirstVertex::Auto) return choice == FirstVertex::ImageSpace;
    if (camera_moves) return false;
    for (const auto& shape : scene.shapes)
        if (params.moves(*shape) && has_texture(*shape, [](const Texture& t) { return !t.is_continuous(); })) return false;
    return true;
}

} // namespace penumbra
