// Multiple importance sampling over the (s, t) strategies of bidirectional path tracing (Veach 1997,
// §10.2.1): the weight of strategy s on a path x_0 ... x_k is p_s^β / Σ_i p_i^β (β = 2: power heuristic,
// Eq. 9.13; β = 1: balance heuristic), with the ratios p_{i+1} / p_i = p←(x_i) / p→(x_i) of the densities of
// x_i sampled from the light side and from the camera side (Eq. 10.9), walked from s in both directions as in
// pbrt-v3.
#pragma once
#include "render/bdpt_subpaths.h"

namespace penumbra {

// One strategy's path: s light subpath vertices, t camera subpath vertices, their connection.
struct Strategy {
    int s = 0, t = 0;
    const std::vector<PathVertex>* light = nullptr;
    const std::vector<PathVertex>* camera = nullptr;
    const PathVertex* light_sample = nullptr;  // replaces y_0 (s = 1, t >= 2: a fresh emitter sample)
    const PathVertex* camera_sample = nullptr; // replaces z_0 (t = 1: the sensor sample)
    const Emitter* emitter = nullptr;          // the emitter at the light end
    // Free-flight factors of the connecting segment: of the camera-side endpoint from the light-side one,
    // and the reverse.
    float ff_to_camera = 1.f, ff_to_light = 1.f;
    float camera_pdf_dir = 0.f; // t = 1: the sensor's direction density toward the light-side endpoint
};

float mis_weight(const BDPTContext& ctx, const Strategy& strategy);

} // namespace penumbra
