#include "render/bdpt_mis.h"

#include <cmath>
#include <vector>

namespace penumbra {

namespace {

float ratio(float num, float den) { return (num != 0.f ? num : 1.f) / (den != 0.f ? den : 1.f); }

} // namespace

float mis_weight(const BDPTContext& ctx, const Strategy& st) {
    const int s = st.s, t = st.t, n = s + t; // x_0 ... x_{n-1}, light end first
    if (ctx.settings.strategy_s >= 0) return 1.f;
    auto vertex = [&](int i) -> const PathVertex& {
        if (i < s) return (i == 0 && st.light_sample) ? *st.light_sample : (*st.light)[size_t(i)];
        const int j = n - 1 - i;
        return (j == 0 && st.camera_sample) ? *st.camera_sample : (*st.camera)[size_t(j)];
    };
    thread_local std::vector<float> from_light, from_camera;
    thread_local std::vector<char> delta;
    from_light.resize(size_t(n));
    from_camera.resize(size_t(n));
    delta.resize(size_t(n));
    for (int i = 0; i < n; ++i) {
        const PathVertex& v = vertex(i);
        from_light[size_t(i)] = i < s ? v.pdf_fwd : v.pdf_rev;
        from_camera[size_t(i)] = i < s ? v.pdf_rev : v.pdf_fwd;
        delta[size_t(i)] = v.delta;
    }

    // The densities the connection changes: of pt = x_s and its predecessor x_{s+1} from the light side, of
    // qs = x_{s-1} and x_{s-2} from the camera side.
    const PathVertex& pt = vertex(s);
    if (s > 0) {
        const PathVertex& qs = vertex(s - 1);
        if (t >= 2) {
            from_light[s] =
                s == 1 ? light_emission_density(ctx, st.emitter, qs, pt, st.ff_to_camera)
                       : scattering_density(qs, qs.wi, pt, st.ff_to_camera, TransportMode::Importance);
            from_light[s + 1] = scattering_density(pt, direction_to(pt, qs), vertex(s + 1), pt.ff_rev,
                                                   TransportMode::Importance);
            from_camera[s - 1] = scattering_density(pt, pt.wi, qs, st.ff_to_light, TransportMode::Radiance);
        } else {
            from_camera[s - 1] = to_area_density(pt, qs, st.camera_pdf_dir, st.ff_to_light);
        }
        if (s >= 2)
            from_camera[s - 2] = scattering_density(qs, direction_to(qs, pt), vertex(s - 2), qs.ff_rev,
                                                    TransportMode::Radiance);
        delta[s - 1] = false;
    } else {
        from_light[0] = light_origin_density(ctx.scene, st.emitter, pt, vertex(1));
        from_light[1] = light_emission_density(ctx, st.emitter, pt, vertex(1), pt.ff_rev);
    }
    delta[s] = false;

    // Strategy i connects x_{i-1} and x_i (i = 0: the camera subpath reaches the light). t = 0 is not used
    // (the sensor cannot be hit), nor t = 1 for meters; the light seen by the camera through light tracing
    // (i = 1, n = 2) only for area lights; delta vertices cannot be connected, delta lights cannot be hit.
    const bool area_light = st.emitter->shape() != nullptr;
    auto usable = [&](int i) {
        // t = 1 needs the vertex next to the sensor to project onto the image (within the clip range).
        if (i >= n || (i == n - 1 && (!ctx.sensor_connects || !(from_camera[size_t(n - 2)] > 0.f))))
            return false;
        if (i == 0) return !st.emitter->is_delta();
        if (i == 1 && n == 2) return area_light;
        return !delta[size_t(i - 1)] && !delta[size_t(i)];
    };
    const bool power = ctx.settings.heuristic == MISHeuristic::Power;
    auto density_ratio = [&](float num, float den) {
        const float q = ratio(num, den);
        return power ? q * q : q;
    };
    float sum = 1.f, r = 1.f;
    for (int i = s + 1; i < n; ++i) {
        r *= density_ratio(from_light[size_t(i - 1)], from_camera[size_t(i - 1)]);
        if (usable(i)) sum += r;
    }
    r = 1.f;
    for (int i = s - 1; i >= 0; --i) {
        r *= density_ratio(from_camera[size_t(i)], from_light[size_t(i)]);
        if (usable(i)) sum += r;
    }
    const float w = 1.f / sum;
    return std::isfinite(w) ? w : 0.f;
}

} // namespace penumbra
