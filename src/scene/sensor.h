// Sensors: perspective (pinhole) and orthographic cameras, Mitsuba 3 conventions
// (camera looks along local +z, local +x is left, film origin at the top-left corner).
#pragma once
#include "core/transform.h"
#include "scene/film.h"
#include "scene/interaction.h"

#include <memory>

namespace penumbra {

class SamplerDesc : public Object {
public:
    ObjectKind kind() const override { return ObjectKind::Sampler; }
    int sample_count = 4;
    uint64_t seed = 0;
};

class Sensor : public Object {
public:
    ObjectKind kind() const override { return ObjectKind::Sensor; }
    Transform to_world;
    std::shared_ptr<Film> film;
    std::shared_ptr<SamplerDesc> sampler;
    float near_clip = 1e-2f, far_clip = 1e4f;

    // Primary ray through continuous film position `film_pos` (pixels, [0,W]x[0,H]); weight is 1 for pinholes.
    virtual std::pair<Ray, Color3f> sample_ray(const Vec2f& film_pos, const Vec2f& aperture_sample) const = 0;
    // Light tracing: connect `ref` to the sensor. ds.uv is the film position in pixels, ds.pdf the solid-angle
    // density (1 for a pinhole: a delta position), and the weight is W_e / pdf with the importance W_e normalized
    // so that it integrates to 1 over the whole film. Zero weight if ref projects outside the film.
    virtual std::pair<DirectionSample3f, Color3f> sample_direction(const Interaction3f& ref, const Vec2f& u) const = 0;
    // Projection of a world point to continuous film coordinates (pixels); false if behind or outside.
    virtual bool project(const Vec3f& p, Vec2f& film_pos) const = 0;
};

} // namespace penumbra
