// Mitsuba 3 `heterogeneous` medium: extinction and albedo from volumes (typically `gridvolume`).
//
// Parameters:
//   sigma_t                  float/spectrum/volume  1      extinction (1/length, before `scale`), >= 0
//   albedo                   float/spectrum/volume  0.75   single-scattering albedo sigma_s / sigma_t
//   scale                    float                  1      multiplies sigma_t (differentiable as `scale`)
//   sample_emitters          boolean                true   next-event estimation inside the medium
//   has_spectral_extinction  boolean                true   accepted: RGB rendering tracks per-channel
//                                                          extinction against one grey majorant either way
//   (nested phase)           phase                  isotropic
//
// sigma_t is zero outside the world bounding box of the sigma_t volume (when it has one: a grid), as in
// Mitsuba, whose heterogeneous medium only samples the ray's overlap with that box. Majorants: one segment
// per block of the grid's coarse grid of maxima crossed by the ray (scaled), zero outside the box.
#include "scene/media_loading.h"

namespace penumbra {

namespace {

class HeterogeneousMedium final : public MediumBase<HeterogeneousMedium> {
  public:
    std::shared_ptr<Volume> sigma_t_volume, albedo_volume;
    float scale = 1.f;
    int scale_index = -1;

    bool is_homogeneous() const override { return false; }
    template <typename T> Color3<T> sigma_t_t(const Vec3<T>& p) const {
        if (!inside_support(Vec3f(detach(p.x), detach(p.y), detach(p.z)))) return Color3<T>(T(0.f));
        return sigma_t_volume->eval(p) * param_value<T>(scale, scale_index);
    }
    template <typename T> Color3<T> albedo_t(const Vec3<T>& p) const { return albedo_volume->eval(p); }

    void majorants(const Vec3f& o, const Vec3f& d, float tmin, float tmax,
                   const MajorantVisitor& f) const override {
        if (!(tmin < tmax)) return;
        const BoundingBox3f box = sigma_t_volume->bbox();
        float a = tmin, b = tmax;
        if (box.is_valid()) {
            // The box grown by a slack far above the rounding of o + t d near it, so that points of the zero
            // segments never round into the box (where sigma_t is not zero); the margin is covered by the
            // grid's bound outside its unit cube.
            const float slack = 1e-5f * (max_component(abs(o)) + max_component(box.hi - box.lo) +
                                         max_component(max(abs(box.lo), abs(box.hi))));
            const BoundingBox3f grown{box.lo - Vec3f(slack), box.hi + Vec3f(slack)};
            float t0, t1;
            if (!grown.intersect(o, d, t0, t1) || !(std::max(t0, tmin) < std::min(t1, tmax))) {
                f(tmin, tmax, 0.f);
                return;
            }
            a = std::max(t0, tmin);
            b = std::min(t1, tmax);
        }
        if (tmin < a && !f(tmin, a, 0.f)) return;
        bool go_on = true;
        sigma_t_volume->max_segments(o, d, a, b, [&](float s0, float s1, float bound) {
            go_on = f(s0, s1, bound * scale);
            return go_on;
        });
        if (go_on && b < tmax) f(b, tmax, 0.f);
    }

    void traverse(ParamVisitor& v) override {
        v.put_object("sigma_t", sigma_t_volume.get());
        v.put_object("albedo", albedo_volume.get());
        v.put("scale", &scale, 1, &scale_index);
        if (phase) v.put_object("phase_function", phase.get());
    }

  private:
    bool inside_support(const Vec3f& p) const {
        const BoundingBox3f box = sigma_t_volume->bbox();
        if (!box.is_valid()) return true;
        return p.x >= box.lo.x && p.y >= box.lo.y && p.z >= box.lo.z && p.x <= box.hi.x && p.y <= box.hi.y &&
               p.z <= box.hi.z;
    }
};

} // namespace

std::shared_ptr<Object> make_heterogeneous_medium(const Properties& props, const LoadContext& ctx) {
    auto medium = std::make_shared<HeterogeneousMedium>();
    medium->sigma_t_volume = get_volume(props, "sigma_t", Color3f(1.f));
    medium->albedo_volume = get_volume(props, "albedo", Color3f(0.75f));
    if (!(medium->sigma_t_volume->min() >= 0.f))
        props.raise("sigma_t", "the extinction must be non-negative (the sigma_t volume's minimum is " +
                                   std::to_string(medium->sigma_t_volume->min()) + ")");
    medium->scale = props.get_float("scale", 1.f);
    if (!(medium->scale >= 0.f) || !std::isfinite(medium->scale))
        props.raise("scale", "'scale' must be finite and non-negative");
    medium->sample_emitters = props.get_bool("sample_emitters", true);
    props.get_bool("has_spectral_extinction", true);
    medium->phase = get_phase(props, ctx);
    return medium;
}

} // namespace penumbra
