// The BSDF plugins: constructors from plain values (used by the factory and by tests) and loaders from
// scene-file properties (one pair per plugin file, the parameter table at the top of each file).
#pragma once
#include "core/microfacet.h"
#include "scene/bsdf.h"
#include "scene/factory.h"
#include "scene/texture.h"

#include <memory>

namespace penumbra {

using TexturePtr = std::shared_ptr<Texture>;
using BSDFPtr = std::shared_ptr<BSDF>;

// Microfacet roughness as Mitsuba parses it: `distribution`, `alpha` or `alpha_u`/`alpha_v`, `sample_visible`.
struct RoughnessParams {
    MicrofacetType type = MicrofacetType::Beckmann;
    TexturePtr alpha_u, alpha_v;
    bool sample_visible = true;
};

BSDFPtr make_diffuse(TexturePtr reflectance);
BSDFPtr make_conductor(TexturePtr eta, TexturePtr k, TexturePtr specular_reflectance);
BSDFPtr make_roughconductor(const RoughnessParams& rough, TexturePtr eta, TexturePtr k, TexturePtr specular_reflectance);
BSDFPtr make_dielectric(float eta, TexturePtr specular_reflectance, TexturePtr specular_transmittance);
BSDFPtr make_roughdielectric(const RoughnessParams& rough, float eta, TexturePtr specular_reflectance,
                             TexturePtr specular_transmittance);
BSDFPtr make_thindielectric(float eta, TexturePtr specular_reflectance, TexturePtr specular_transmittance);
BSDFPtr make_plastic(float eta, TexturePtr diffuse_reflectance, TexturePtr specular_reflectance, bool nonlinear);
BSDFPtr make_roughplastic(MicrofacetType type, float alpha, bool sample_visible, float eta,
                          TexturePtr diffuse_reflectance, TexturePtr specular_reflectance, bool nonlinear);
BSDFPtr make_blendbsdf(TexturePtr weight, BSDFPtr first, BSDFPtr second);
BSDFPtr make_twosided(BSDFPtr front, BSDFPtr back); // back may be null (front used on both sides)
BSDFPtr make_mask(TexturePtr opacity, BSDFPtr nested);
BSDFPtr make_null_bsdf();
BSDFPtr make_normalmap(TexturePtr normalmap, BSDFPtr nested);
BSDFPtr make_bumpmap(TexturePtr height, float scale, BSDFPtr nested);
// The parameters `principled` and `principledthin` share (Mitsuba's defaults). has_spec_trans is Mitsuba's
// lobe flag: set when the scene gives spec_trans other than the float 0 (it adds the transmission flag and
// keeps eta away from 1).
struct PrincipledShared {
    TexturePtr base_color = make_constant_texture(Color3f(0.5f));
    TexturePtr roughness = make_constant_texture(Color3f(0.5f));
    TexturePtr anisotropic = make_constant_texture(Color3f(0.f));
    TexturePtr spec_trans = make_constant_texture(Color3f(0.f));
    TexturePtr spec_tint = make_constant_texture(Color3f(0.f));
    TexturePtr sheen = make_constant_texture(Color3f(0.f));
    TexturePtr sheen_tint = make_constant_texture(Color3f(0.f));
    TexturePtr flatness = make_constant_texture(Color3f(0.f));
    bool has_spec_trans = false;
};
// The parameters of `principled` (Mitsuba's defaults).
struct PrincipledParams : PrincipledShared {
    TexturePtr metallic = make_constant_texture(Color3f(0.f));
    TexturePtr clearcoat = make_constant_texture(Color3f(0.f));
    TexturePtr clearcoat_gloss = make_constant_texture(Color3f(0.f));
    bool eta_given = false; // the IOR is `eta` (else `specular`)
    float eta = 1.5f, specular = 0.5f;
    float spec_rate = 1.f, clearcoat_rate = 1.f, diffuse_rate = 1.f; // lobe sampling rates
};
// The parameters of `principledthin` (Mitsuba's defaults).
struct PrincipledThinParams : PrincipledShared {
    TexturePtr eta = make_constant_texture(Color3f(1.5f));
    TexturePtr diff_trans = make_constant_texture(Color3f(0.f));
    float spec_reflect_rate = 1.f, spec_trans_rate = 1.f; // lobe sampling rates
    float diffuse_reflect_rate = 1.f, diffuse_trans_rate = 1.f;
};
BSDFPtr make_principled(const PrincipledParams& params);
BSDFPtr make_principledthin(const PrincipledThinParams& params);

BSDFPtr load_diffuse(const Properties& props);
BSDFPtr load_conductor(const Properties& props);
BSDFPtr load_roughconductor(const Properties& props);
BSDFPtr load_dielectric(const Properties& props);
BSDFPtr load_roughdielectric(const Properties& props);
BSDFPtr load_thindielectric(const Properties& props);
BSDFPtr load_plastic(const Properties& props);
BSDFPtr load_roughplastic(const Properties& props);
BSDFPtr load_blendbsdf(const Properties& props);
BSDFPtr load_twosided(const Properties& props);
BSDFPtr load_mask(const Properties& props);
BSDFPtr load_null_bsdf(const Properties& props);
BSDFPtr load_normalmap(const Properties& props);
BSDFPtr load_bumpmap(const Properties& props);
BSDFPtr load_principled(const Properties& props);
BSDFPtr load_principledthin(const Properties& props);

// --- parameter helpers shared by the loaders (factory.cpp) ---
// Mitsuba's named dielectric IORs ("bk7", "air", ...); a float value is used as is.
float lookup_ior(const Properties& props, const std::string& name, const std::string& default_name);
// Relative IOR int_ior / ext_ior with Mitsuba's checks (positive and different).
float relative_ior(const Properties& props, const std::string& default_int);
// `distribution`: "beckmann" (default) or "ggx".
MicrofacetType parse_distribution(const Properties& props);
// `distribution`, `alpha` / `alpha_u`, `alpha_v` (textures) and `sample_visible`.
RoughnessParams parse_roughness(const Properties& props);
// The parameters of the smooth and thin dielectrics: relative IOR (interior default "bk7"),
// `specular_reflectance` and `specular_transmittance` (default 1).
struct DielectricParams {
    float eta;
    TexturePtr specular_reflectance, specular_transmittance;
};
DielectricParams parse_dielectric(const Properties& props);
// The coating and base parameters of plastic and roughplastic: relative IOR (interior default
// "polypropylene"), `specular_reflectance` (1), `diffuse_reflectance` (0.5) and `nonlinear` (false).
struct PlasticParams {
    float eta;
    TexturePtr specular_reflectance, diffuse_reflectance;
    bool nonlinear;
};
PlasticParams parse_plastic(const Properties& props);
// Conductor `material` (named, e.g. "Au") or explicit `eta` / `k` (defaults 0 / 1: a perfect mirror).
void parse_conductor_ior(const Properties& props, TexturePtr& eta, TexturePtr& k);
// Lists the roughness textures: "alpha" when isotropic (one texture), else "alpha_u" and "alpha_v".
inline void traverse_roughness(ParamVisitor& v, const RoughnessParams& r) {
    if (r.alpha_u == r.alpha_v) {
        v.put_object("alpha", r.alpha_u.get());
    } else {
        v.put_object("alpha_u", r.alpha_u.get());
        v.put_object("alpha_v", r.alpha_v.get());
    }
}
// Nested BSDF children in declaration order.
std::vector<BSDFPtr> nested_bsdfs(const Properties& props);

} // namespace penumbra
