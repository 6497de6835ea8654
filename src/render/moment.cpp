// `moment`: first and second moments of nested integrators' samples (Mitsuba 3's `moment`).
//
// | parameter | type       | default | meaning |
// |-----------|------------|---------|-----------------------------------------------------------------------|
// | (nested)  | integrator | —       | one or more camera-driven integrators (path, direct, aov, moment) |
//
// Layers, named as Mitsuba names its AOVs, for each nested integrator called <n> (its `name` attribute, or
// `_arg_<i>` when unnamed): <n>.<aov> for each of its AOV layers, then <n> with channels X,Y,Z (its main
// image converted to CIE XYZ); after those of all nested integrators, m2_<layer> for each of them: the pixel
// average of the squared sample values. The main image is the first nested integrator's. Var = m2_<n> -
// <n>^2.
#include "render/moment.h"

namespace penumbra {

MomentIntegrator::MomentIntegrator(const IntegratorSettings& settings) {
    names_.push_back("");
    channels_.push_back("RGB");
    for (const auto& [name, nested_settings] : settings.nested) {
        std::shared_ptr<SamplingIntegrator> nested = make_sampling_integrator(*nested_settings);
        const std::vector<std::string> names = nested->layer_names(), channels = nested->layer_channels();
        Nested entry{nested, {}};
        for (size_t l = 0; l < names.size(); ++l) {
            entry.is_main.push_back(names[l].empty());
            if (!names[l].empty()) {
                names_.push_back(name + "." + names[l]);
                channels_.push_back(channels[l]);
            }
        }
        names_.push_back(name);
        channels_.push_back("XYZ");
        nested_.push_back(std::move(entry));
    }
    first_moments_ = names_.size() - 1;
    for (size_t l = 1; l <= first_moments_; ++l) {
        names_.push_back("m2_" + names_[l]);
        channels_.push_back(channels_[l]);
    }
}

void MomentIntegrator::sample(const Scene& scene, Sampler& sampler, const Ray& ray, Color3f* out,
                              RayCounter& rays) const {
    Color3f* first = out + 1;
    std::vector<Color3f> values;
    for (size_t i = 0; i < nested_.size(); ++i) {
        const Nested& n = nested_[i];
        values.resize(n.is_main.size());
        n.integrator->sample(scene, sampler, ray, values.data(), rays);
        Color3f main(0.f); // an integrator without a main image (aov without a nested one) contributes black
        for (size_t l = 0; l < values.size(); ++l)
            if (n.is_main[l])
                main = values[l];
            else
                *first++ = values[l];
        if (i == 0) out[0] = main;
        *first++ = srgb_to_xyz(main);
    }
    // Second moments: per-sample squares, averaged by the film like every layer.
    for (size_t l = 1; l <= first_moments_; ++l)
        out[l + first_moments_] = out[l] * out[l];
}

} // namespace penumbra
