#include "diff/first_vertex.h"

#include "render/light_medium.h"
#include "scene/texture.h"

namespace penumbra {

FirstVertex parse_first_vertex(const std::string& name) {
    if (name == "auto") return FirstVertex::Auto;
    if (name == "image") return FirstVertex::ImageSpace;
    if (name == "material") return FirstVertex::Material;
    throw Error("unknown first-vertex form '" + name + "' (expected auto, image or material)");
}

bool moves_geometry(const Scene& scene, const Parameters& params) {
    if (!params.sensor_motions().empty()) return true;
    for (const auto& shape : scene.shapes)
        if (params.moves(*shape)) return true;
    for (const auto& emitter : scene.emitters)
        if (!params.emitter_motions(emitter.get()).empty()) return true; // its shadows move
    return false;
}

namespace {

std::string viewpoint_note(const Scene& scene) {
    return scene.sensor->plugin +
           (scene.sensor->plugin == "thinlens" ? " sensor with a finite aperture" : " sensor");
}

} // namespace

bool image_space_first_vertex(const Scene& scene, const Parameters& params, FirstVertex choice) {
    const bool camera_moves = !params.sensor_motions().empty();
    if (!scene.sensor->projects_points()) {
        if (choice == FirstVertex::Material)
            throw Error("the material-form first vertex needs a single center of projection, not a " +
                        viewpoint_note(scene) + " (use --first-vertex image)");
        if (camera_moves)
            throw Error("derivatives of a moving " + viewpoint_note(scene) + " are not supported");
        for (const auto& shape : scene.shapes)
            if (params.moves(*shape) &&
                has_texture(*shape, [](const Texture& t) { return !t.is_continuous(); }))
                throw Error(
                    "with a " + viewpoint_note(scene) +
                    ", a moving shape with a texture that jumps inside its triangles is not supported");
        return true;
    }
    if (choice == FirstVertex::ImageSpace && camera_moves)
        throw Error("the image-space first vertex needs a static camera: the sensor moves (use "
                    "--first-vertex material)");
    if (choice != FirstVertex::Auto) return choice == FirstVertex::ImageSpace;
    if (camera_moves) return false;
    for (const auto& shape : scene.shapes)
        if (params.moves(*shape) && has_texture(*shape, [](const Texture& t) { return !t.is_continuous(); }))
            return false;
    // A point or spot light moving in a medium carries the medium near it (diff/volume_motion.h); the
    // camera's first medium vertex follows that motion only in material form (in image space the single
    // scattering next to the light has the heavy-tailed 1/ℓ³ derivative of I/ℓ²).
    if (scene_has_media(scene))
        for (const auto& e : scene.emitters)
            if (e->is_delta() && !e->is_infinite() && !params.emitter_motions(e.get()).empty()) return false;
    return true;
}

void require_pinhole(const Scene& scene, const Parameters& params, const std::string& term) {
    if (!scene.sensor->projects_points() && moves_geometry(scene, params))
        throw Error("the " + term +
                    " boundary term connects points to a single center of projection, which a " +
                    viewpoint_note(scene) + " does not have: use --method interior, or a perspective sensor");
}

} // namespace penumbra
