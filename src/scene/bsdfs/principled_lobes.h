// Lobes shared by the `principled` and `principledthin` BSDFs (Burley 2012, "Physically Based Shading at
// Disney"; Burley 2015, "Extending the Disney BRDF to a BSDF with Integrated Subsurface Scattering"), with
// Mitsuba 3's conventions (src/bsdfs/principledhelpers.h): Schlick Fresnel, the GTR1 clearcoat distribution,
// the roughness-to-alpha map, and the diffuse (retro-reflection, fake subsurface) and sheen lobes.
// Templated on the scalar type; sampling is float only.
#pragma once
#include "core/microfacet.h"
#include "core/vector.h"
#include "scene/bsdfs/bsdfs.h"
#include "scene/properties.h"

#include <algorithm>
#include <cmath>

namespace penumbra::principled {

// Schlick's weight (1 − cos)^5, cos clamped to [0, 1] (Schlick 1994).
template <typename T> T schlick_weight(const T& cos_theta) {
    const T m = clamp(T(1) - cos_theta, 0.f, 1.f);
    return sqr(sqr(m)) * m;
}

// R0 = ((eta − 1) / (eta + 1))², the normal-incidence reflectance of relative IOR eta.
template <typename T> T schlick_r0(const T& eta) { return sqr((eta - T(1)) / (eta + T(1))); }

// Schlick's Fresnel R0 + (1 − R0) (1 − cos)^5 at microfacet cosine cos_i for relative IOR eta; seen from the
// denser side (eta_it < 1) the refracted cosine is used, as Mitsuba does.
template <typename T, typename C> C schlick_fresnel(const C& r0, const T& cos_i, const T& eta) {
    using std::abs;
    const T eta_it = cos_i >= T(0) ? eta : T(1) / eta;
    const T cos_t = safe_sqrt(T(1) - (T(1) - cos_i * cos_i) / sqr(eta_it));
    const T w = schlick_weight(eta_it > T(1) ? abs(cos_i) : cos_t);
    return r0 + (C(T(1)) - r0) * w;
}

// base_color / luminance(base_color) (1 where the luminance is 0): the hue used by spec_tint and sheen_tint.
template <typename T> Color3<T> tint_color(const Color3<T>& base) {
    const T lum = luminance(base);
    return lum > T(0) ? base / lum : Color3<T>(T(1));
}

template <typename T> Color3<T> sqrt_color(const Color3<T>& c) {
    return {safe_sqrt(c.x), safe_sqrt(c.y), safe_sqrt(c.z)};
}

// Disney roughness to GGX alphas (Burley 2012): α = roughness², stretched by aspect = sqrt(1 − 0.9
// anisotropic) into α_u = α / aspect, α_v = α · aspect; each at least 0.001.
template <typename T>
MicrofacetDistribution<T> specular_distribution(const T& roughness, const T& anisotropic) {
    using std::sqrt;
    const T a = sqr(roughness), aspect = sqrt(T(1) - T(0.9f) * anisotropic);
    MicrofacetDistribution<T> d;
    d.type = MicrofacetType::GGX;
    d.alpha_u = std::max(T(0.001f), a / aspect);
    d.alpha_v = std::max(T(0.001f), a * aspect);
    d.sample_visible = true;
    return d;
}

// GTR1 (Berry) distribution of the clearcoat (Burley 2012): D(m) = (α² − 1) / (π log(α²) (1 + (α² − 1)
// cos²θ_m)), sampled proportionally to D(m) cos θ_m; α = lerp(0.1, 0.001, clearcoat_gloss).
template <typename T> struct GTR1 {
    T alpha;
    T D(const Vec3<T>& m) const {
        using std::log;
        const T a2 = sqr(alpha);
        const T d = (a2 - T(1)) / (T(Pi) * log(a2) * (T(1) + (a2 - T(1)) * sqr(m.z)));
        return d * m.z > T(1e-20f) ? d : T(0);
    }
    T pdf(const Vec3<T>& m) const { return m.z < T(0) ? T(0) : m.z * D(m); }
    // cos²θ = (1 − α^(2(1 − u_y))) / (1 − α²), φ = 2π u_x.
    static Vec3f sample(float alpha, const Vec2f& u) {
        const float a2 = alpha * alpha;
        const float cos2 = (1.f - std::pow(a2, 1.f - u.y)) / (1.f - a2);
        const float sin_t = std::sqrt(std::max(0.f, 1.f - cos2)), cos_t = std::sqrt(std::max(0.f, cos2));
        const float phi = 2.f * Pi * u.x;
        return {std::cos(phi) * sin_t, std::sin(phi) * sin_t, cos_t};
    }
};
template <typename T> T clearcoat_alpha(const T& gloss) {
    return T(0.1f) * (T(1) - gloss) + T(0.001f) * gloss;
}

// Clearcoat masking: separable Smith GGX with the fixed α = 0.25, in terms of cos θ alone as in Burley 2012
// and Mitsuba: G1(v) = 2 / (1 + sqrt(1 + α² (1 − cos²θ) / cos²θ)), 0 where v sees the back of m.
template <typename T> T clearcoat_G1(const Vec3<T>& v, const Vec3<T>& m) {
    using std::abs;
    using std::sqrt;
    if (!(dot(v, m) * v.z > T(0))) return T(0);
    const T c2 = sqr(abs(v.z));
    if (c2 == T(1)) return T(1);
    return T(2) / (T(1) + sqrt(T(1) + T(0.0625f) * (T(1) - c2) / c2));
}
template <typename T> T clearcoat_G(const Vec3<T>& wi, const Vec3<T>& wo, const Vec3<T>& m) {
    return clearcoat_G1(wi, m) * clearcoat_G1(wo, m);
}

// Whether microfacet m (flipped to wi's side of the macro surface) is seen by wi and by wo on the same side
// (reflection) or on opposite sides (transmission).
template <typename T>
bool microfacet_compatible(const Vec3<T>& m, const Vec3<T>& wi, const Vec3<T>& wo, bool reflection) {
    const Vec3<T> ms = wi.z >= T(0) ? m : -m;
    return dot(wi, ms) > T(0) && (reflection ? dot(wo, ms) > T(0) : dot(wo, ms) < T(0));
}

// The diffuse lobe's shape without base_color / π (Burley 2012 and 2015, in Mitsuba's form): the
// Schlick-shaped diffuse (1 − F_i/2)(1 − F_o/2) plus retro-reflection R_r (F_o + F_i + F_o F_i (R_r − 1)),
// R_r = 2 roughness cos²θ_d, blended by `flatness` with the Hanrahan-Krueger-like fake subsurface
// 1.25 (F_ss (1 / (cos_i + cos_o) − 0.5) + 0.5), F_ss = lerp(1, R_r/2, F_o) lerp(1, R_r/2, F_i).
template <typename T>
T diffuse_shape(const T& cos_i, const T& cos_o, const T& cos_d, const T& roughness, const T& flatness) {
    const T fi = schlick_weight(cos_i), fo = schlick_weight(cos_o);
    const T f_diff = (T(1) - T(0.5f) * fi) * (T(1) - T(0.5f) * fo);
    const T rr = T(2) * roughness * sqr(cos_d);
    const T f_retro = rr * (fo + fi + fo * fi * (rr - T(1)));
    const T fss90 = T(0.5f) * rr;
    const T fss = (T(1) + (fss90 - T(1)) * fo) * (T(1) + (fss90 - T(1)) * fi);
    const T f_ss = T(1.25f) * (fss * (T(1) / (cos_o + cos_i) - T(0.5f)) + T(0.5f));
    return (T(1) - flatness) * (f_diff + f_retro) + flatness * f_ss;
}

// Sheen (Burley 2012): sheen · lerp(1, tint, sheen_tint) · (1 − cos θ_d)^5, without the cosine.
template <typename T>
Color3<T> sheen_value(const T& sheen, const T& sheen_tint, const Color3<T>& base, const T& cos_d) {
    using std::abs;
    const Color3<T> c = Color3<T>(T(1) - sheen_tint) + tint_color(base) * sheen_tint;
    return c * (sheen * schlick_weight(abs(cos_d)));
}

// Mitsuba's `get_flag`: a lobe parameter is active unless absent or given as the float 0 (a texture is
// active).
inline bool lobe_enabled(const Properties& props, const std::string& name) {
    if (!props.has(name)) return false;
    const Properties::Tag tag = props.type(name);
    if (tag == Properties::Tag::Float || tag == Properties::Tag::Integer) return props.get_float(name) != 0.f;
    return true;
}

// Reads the parameters both principled models take, with Mitsuba's names and defaults.
inline void load_shared(const Properties& props, PrincipledShared& p) {
    p.base_color = props.get_texture("base_color", Color3f(0.5f));
    p.roughness = props.get_texture("roughness", Color3f(0.5f));
    p.anisotropic = props.get_texture("anisotropic", Color3f(0.f));
    p.has_spec_trans = lobe_enabled(props, "spec_trans");
    p.spec_trans = props.get_texture("spec_trans", Color3f(0.f));
    p.spec_tint = props.get_texture("spec_tint", Color3f(0.f));
    p.sheen = props.get_texture("sheen", Color3f(0.f));
    p.sheen_tint = props.get_texture("sheen_tint", Color3f(0.f));
    p.flatness = props.get_texture("flatness", Color3f(0.f));
}

// Lists the shared parameters under Mitsuba's keys (after each model's own leading ones, as Mitsuba does).
inline void traverse_shared(ParamVisitor& v, const PrincipledShared& p) {
    v.put_object("base_color", p.base_color.get());
    v.put_object("anisotropic", p.anisotropic.get());
    v.put_object("spec_tint", p.spec_tint.get());
    v.put_object("sheen", p.sheen.get());
    v.put_object("sheen_tint", p.sheen_tint.get());
    v.put_object("spec_trans", p.spec_trans.get());
    v.put_object("flatness", p.flatness.get());
}

// A lobe sampling rate (default 1); negative rates are a LoadError.
inline float sampling_rate(const Properties& props, const char* name) {
    const float rate = props.get_float(name, 1.f);
    if (!(rate >= 0.f)) props.raise(name, "sampling rates must be >= 0");
    return rate;
}

} // namespace penumbra::principled
