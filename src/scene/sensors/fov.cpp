// Parameters shared by the perspective and thinlens cameras: the field of view (Mitsuba's parse_fov()), the
// principal point offset, and the check that a camera transform has no scale.
#include "scene/sensors/sensor_common.h"

#include <cmath>
#include <cstdlib>

namespace penumbra {

float parse_x_fov(const Properties& props, double aspect) {
    if (props.has("fov") && props.has("focal_length"))
        props.raise("focal_length",
                    "specify either a focal length ('focal_length') or a field of view ('fov')");
    double fov;
    std::string axis;
    if (props.has("fov")) {
        fov = props.get_float("fov");
        axis = props.get_string("fov_axis", "x");
        if (axis == "smaller")
            axis = aspect > 1 ? "y" : "x";
        else if (axis == "larger")
            axis = aspect > 1 ? "x" : "y";
    } else {
        std::string f = props.get_string("focal_length", "50mm");
        if (f.size() > 2 && f.compare(f.size() - 2, 2, "mm") == 0) f.resize(f.size() - 2);
        char* end = nullptr;
        const double value = std::strtod(f.c_str(), &end);
        if (f.empty() || *end != '\0' || !(value > 0))
            props.raise("focal_length", "could not parse the focal length (expected '<x>mm' with x > 0)");
        // Diagonal of 35mm film (36 x 24 mm) seen at distance `value`.
        fov = 2.0 * std::atan(std::sqrt(36.0 * 36.0 + 24.0 * 24.0) / (2.0 * value)) * 180.0 / Pi;
        axis = "diagonal";
    }
    const double half = 0.5 * fov * Pi / 180.0;
    double result;
    if (axis == "x") {
        result = fov;
    } else if (axis == "y") {
        result = 2.0 * std::atan(std::tan(half) * aspect) * 180.0 / Pi;
    } else if (axis == "diagonal") {
        const double width = 2.0 * std::tan(half) / std::sqrt(1.0 + 1.0 / (aspect * aspect));
        result = 2.0 * std::atan(0.5 * width) * 180.0 / Pi;
    } else {
        props.raise("fov_axis",
                    "invalid fov_axis '" + axis + "' (expected 'x', 'y', 'diagonal', 'smaller' or 'larger')");
    }
    if (!(result > 0.0 && result < 180.0))
        props.raise(props.has("fov") ? "fov" : "focal_length",
                    "the horizontal field of view must be in (0, 180) degrees");
    return float(result);
}

namespace {

// Mitsuba's Transform::has_scale(): the linear part is not orthonormal (M M^T != I within 1e-3).
bool has_scale(const Transform& t) {
    const auto& m = t.matrix.m;
    for (int i = 0; i < 3; ++i)
        for (int j = i; j < 3; ++j) {
            const float sum = m[i][0] * m[j][0] + m[i][1] * m[j][1] + m[i][2] * m[j][2];
            if (std::abs(sum - (i == j ? 1.f : 0.f)) > 1e-3f) return true;
        }
    return false;
}

} // namespace

PerspectiveParameters load_perspective_parameters(const Properties& props, const Sensor& camera) {
    if (has_scale(camera.to_world))
        props.raise("to_world", "scale factors in the camera-to-world transformation are not allowed");
    const Vec2i size = camera.film->full_size;
    return {parse_x_fov(props, double(size.x) / size.y),
            Vec2f(props.get_float("principal_point_offset_x", 0.f), props.get_float("principal_point_offset_y", 0.f))};
}

} // namespace penumbra
