// Film (hdrfilm) and pixel reconstruction filters (box, tent, gaussian) with Mitsuba 3's parameters.
#pragma once
#include "core/scalar.h"
#include "core/vector.h"
#include "scene/object.h"

#include <memory>
#include <vector>

namespace penumbra {

class ReconstructionFilter : public Object {
public:
    ObjectKind kind() const override { return ObjectKind::RFilter; }
    float radius() const { return radius_; }
    // Separable 1D filter profile (not normalized), zero beyond radius(); templated for the filter derivative.
#define PENUMBRA_FILTER_METHODS(T) virtual T eval(const T& x) const = 0;
    PENUMBRA_FOR_EACH_SCALAR(PENUMBRA_FILTER_METHODS)
#undef PENUMBRA_FILTER_METHODS
    // 2D filter value f(x) f(y) normalized to integrate to 1 over the plane.
    template <typename T> T eval_normalized(const Vec2<T>& offset) const {
        return eval(offset.x) * eval(offset.y) / T(integral_ * integral_);
    }
    // Offset in pixels distributed proportionally to the (normalized, non-negative) filter.
    Vec2f sample(const Vec2f& u) const;

protected:
    void init_sampling(); // tabulates the 1D CDF; call at the end of the constructor
    float radius_ = 0.5f;

private:
    std::vector<float> cdf_;
    std::vector<int> guide_;
    float integral_ = 1.f;
};

// CRTP helper: a filter implements `template <typename T> T eval_t(const T& x) const`.
template <typename Derived> class FilterBase : public ReconstructionFilter {
public:
#define PENUMBRA_FILTER_IMPL(T)                                                                              \
    T eval(const T& x) const override { return static_cast<const Derived*>(this)->template eval_t<T>(x); }
    PENUMBRA_FOR_EACH_SCALAR(PENUMBRA_FILTER_IMPL)
#undef PENUMBRA_FILTER_IMPL
};

class Film : public Object {
public:
    ObjectKind kind() const override { return ObjectKind::Film; }
    // The image: width x height pixels. With a crop window (Mitsuba's crop_offset_x/y, crop_width/height) the
    // image is the crop and shows the region of the full_size frame at crop_offset; sensors project onto the
    // full frame, and film positions (pixels) are relative to the image's top-left corner.
    int width = 768, height = 576;
    Vec2i full_size{768, 576}, crop_offset{0, 0};
    std::shared_ptr<ReconstructionFilter> rfilter;
    std::string to_string() const override;
};

} // namespace penumbra
