// make_bsdf: dispatch on the plugin name, and the parameter helpers shared by the BSDF loaders.
#include "scene/bsdfs/bsdfs.h"

#include "core/spectrum.h"

#include <algorithm>
#include <cctype>
#include <map>

namespace penumbra {

namespace {

// Named dielectric IORs of Mitsuba 3 (include/mitsuba/render/ior.h; Hecht, Optics, at ~589 nm).
const std::map<std::string, float>& ior_table() {
    static const std::map<std::string, float> table = {
        {"vacuum", 1.0f},      {"helium", 1.000036f},        {"hydrogen", 1.000132f},
        {"air", 1.000277f},    {"carbon dioxide", 1.00045f}, {"water", 1.3330f},
        {"acetone", 1.36f},    {"ethanol", 1.361f},          {"carbon tetrachloride", 1.461f},
        {"glycerol", 1.4729f}, {"benzene", 1.501f},          {"silicone oil", 1.52045f},
        {"bromine", 1.661f},   {"water ice", 1.31f},         {"fused quartz", 1.458f},
        {"pyrex", 1.470f},     {"acrylic glass", 1.49f},     {"polypropylene", 1.49f},
        {"bk7", 1.5046f},      {"sodium chloride", 1.544f},  {"amber", 1.55f},
        {"pet", 1.5750f},      {"diamond", 2.419f}};
    return table;
}

float named_ior(const Properties& props, const std::string& param, std::string name) {
    std::transform(name.begin(), name.end(), name.begin(),
                   [](unsigned char c) { return char(std::tolower(c)); });
    const auto it = ior_table().find(name);
    if (it != ior_table().end()) return it->second;
    std::string choices;
    for (const auto& [n, v] : ior_table())
        choices += (choices.empty() ? "" : ", ") + n;
    props.raise(param, "unknown IOR \"" + name + "\" (expected a float or one of: " + choices + ")");
}

// Mitsuba BSDFs that penumbra leaves out on purpose, and why.
const std::map<std::string, std::string>& out_of_scope_bsdfs() {
    static const std::string polarized =
        "polarized BSDFs are out of scope: penumbra is an RGB, unpolarized renderer";
    static const std::map<std::string, std::string> reasons = {
        {"polarizer", polarized},
        {"retarder", polarized},
        {"circular", polarized},
        {"pplastic", polarized},
        {"measured_polarized", polarized},
        {"measured", "tabulated measured BRDFs (RGL .bsdf files) are not implemented"},
        {"hair", "it is meant for curve shapes, which penumbra does not have"}};
    return reasons;
}

} // namespace

float lookup_ior(const Properties& props, const std::string& name, const std::string& default_name) {
    if (!props.has(name)) return named_ior(props, name, default_name);
    using Tag = Properties::Tag;
    const Tag tag = props.type(name);
    if (tag == Tag::Float || tag == Tag::Integer) return props.get_float(name);
    // A material name; any other type is reported as "expected string".
    return named_ior(props, name, props.get_string(name));
}

float relative_ior(const Properties& props, const std::string& default_int) {
    const float int_ior = lookup_ior(props, "int_ior", default_int);
    const float ext_ior = lookup_ior(props, "ext_ior", "air");
    if (int_ior < 0.f || ext_ior < 0.f || int_ior == ext_ior)
        props.raise(props.has("int_ior") ? "int_ior" : "ext_ior",
                    "the interior and exterior indices of refraction must be positive and differ");
    return int_ior / ext_ior;
}

MicrofacetType parse_distribution(const Properties& props) {
    const std::string dist = props.get_string("distribution", "beckmann");
    if (dist == "beckmann") return MicrofacetType::Beckmann;
    if (dist == "ggx") return MicrofacetType::GGX;
    props.raise("distribution",
                "unknown microfacet distribution \"" + dist + "\" (expected \"beckmann\" or \"ggx\")");
}

RoughnessParams parse_roughness(const Properties& props) {
    RoughnessParams r;
    r.type = parse_distribution(props);
    // As Mitsuba: isotropic (one texture, traverse key `alpha`) unless alpha_u or alpha_v is given.
    if (props.has("alpha") || !(props.has("alpha_u") || props.has("alpha_v"))) {
        if (props.has("alpha_u") || props.has("alpha_v"))
            props.raise("alpha", "specify either \"alpha\" or \"alpha_u\"/\"alpha_v\", not both");
        r.alpha_u = r.alpha_v = props.get_texture("alpha", Color3f(0.1f));
    } else {
        r.alpha_u = props.get_texture("alpha_u", Color3f(0.1f));
        r.alpha_v = props.get_texture("alpha_v", Color3f(0.1f));
    }
    r.sample_visible = props.get_bool("sample_visible", true);
    return r;
}

DielectricParams parse_dielectric(const Properties& props) {
    DielectricParams p;
    p.eta = relative_ior(props, "bk7");
    p.specular_reflectance = props.get_texture("specular_reflectance", Color3f(1.f));
    p.specular_transmittance = props.get_texture("specular_transmittance", Color3f(1.f));
    return p;
}

PlasticParams parse_plastic(const Properties& props) {
    PlasticParams p;
    p.eta = relative_ior(props, "polypropylene");
    p.specular_reflectance = props.get_texture("specular_reflectance", Color3f(1.f));
    p.diffuse_reflectance = props.get_texture("diffuse_reflectance", Color3f(0.5f));
    p.nonlinear = props.get_bool("nonlinear", false);
    return p;
}

void parse_conductor_ior(const Properties& props, TexturePtr& eta, TexturePtr& k) {
    const std::string material = props.get_string("material", "none");
    if (props.has("eta") || props.has("k") || material == "none") {
        if (material != "none") props.raise("material", "specify either (eta, k) or a material, not both");
        eta = props.get_texture("eta", Color3f(0.f));
        k = props.get_texture("k", Color3f(1.f));
        return;
    }
    Color3f e, kk;
    if (!conductor_ior(material, e, kk))
        props.raise("material", "unknown conductor material \"" + material +
                                    "\" (expected e.g. Cu, Au, Ag, Al, Cr or none)");
    eta = make_constant_texture(e);
    k = make_constant_texture(kk);
}

std::vector<BSDFPtr> nested_bsdfs(const Properties& props) {
    std::vector<BSDFPtr> result;
    for (const auto& obj : props.objects(ObjectKind::BSDF))
        result.push_back(std::static_pointer_cast<BSDF>(obj));
    return result;
}

std::shared_ptr<Object> make_bsdf(const Properties& props, const LoadContext&) {
    using Loader = BSDFPtr (*)(const Properties&);
    static const std::map<std::string, Loader> loaders = {{"diffuse", load_diffuse},
                                                          {"conductor", load_conductor},
                                                          {"roughconductor", load_roughconductor},
                                                          {"dielectric", load_dielectric},
                                                          {"roughdielectric", load_roughdielectric},
                                                          {"thindielectric", load_thindielectric},
                                                          {"plastic", load_plastic},
                                                          {"roughplastic", load_roughplastic},
                                                          {"blendbsdf", load_blendbsdf},
                                                          {"twosided", load_twosided},
                                                          {"mask", load_mask},
                                                          {"null", load_null_bsdf},
                                                          {"principled", load_principled},
                                                          {"principledthin", load_principledthin},
                                                          {"normalmap", load_normalmap},
                                                          {"bumpmap", load_bumpmap}};
    const auto it = loaders.find(props.plugin());
    if (it != loaders.end()) return it->second(props);
    const auto why = out_of_scope_bsdfs().find(props.plugin());
    if (why == out_of_scope_bsdfs().end()) throw_unsupported_plugin(props, ObjectKind::BSDF);
    throw LoadError(props.location(), "unsupported bsdf plugin '" + props.plugin() + "': " + why->second);
}

} // namespace penumbra
