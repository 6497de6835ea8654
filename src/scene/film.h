// Film (hdrfilm) and pixel reconstruction filters (box, tent, gaussian) with Mitsuba 3's parameters.
#pragma once
#include "core/exr_layers.h"
#include "core/scalar.h"
#include "core/vector.h"
#include "scene/object.h"

#include <cstdint>
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
    // The same restricted to the box [lo, hi] (per axis, lo < hi), with density f / F(box).
    Vec2f sample(const Vec2f& u, const Vec2f& lo, const Vec2f& hi) const;
    // Fraction of the normalized 1D profile's mass below x (piecewise linear between table bins).
    float cdf(float x) const;

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

// The largest film side (width, height, crop sizes and offsets) a scene may ask for.
constexpr int64_t MaxFilmSide = 65536;

class Film : public Object {
public:
    enum class PixelFormat { Luminance, LuminanceAlpha, RGB, RGBA, XYZ, XYZA };
    ObjectKind kind() const override { return ObjectKind::Film; }
    // The image: width x height pixels. With a crop window (Mitsuba's crop_offset_x/y, crop_width/height) the
    // image is the crop and shows the region of the full_size frame at crop_offset; sensors project onto the
    // full frame, and film positions (pixels) are relative to the image's top-left corner.
    int width = 768, height = 576;
    Vec2i full_size{768, 576}, crop_offset{0, 0};
    std::shared_ptr<ReconstructionFilter> rfilter;
    PixelFormat pixel_format = PixelFormat::RGB;
    ComponentFormat component_format = ComponentFormat::Float16;
    // Mitsuba's sample_border: pixels near the edge also integrate the scene beyond the film (the filter over
    // the whole plane); without it (the default) each pixel's filter is cut at the film's edges and
    // renormalized.
    bool sample_border = false;

    bool has_alpha() const {
        return pixel_format == PixelFormat::RGBA || pixel_format == PixelFormat::LuminanceAlpha ||
               pixel_format == PixelFormat::XYZA;
    }
    // Film position (pixels) for an estimate of pixel (x, y), drawn from its filter P_j (see sample_border).
    Vec2f sample_position(int x, int y, const Vec2f& u) const;
    // P_j(s) = f(s - c_j) / F_j: pixel (x, y)'s normalized filter at film position s, with F_j its mass over
    // the film (1 with sample_border; zero off the film otherwise). Templated for the derivative in s; the
    // cut at the film's edge is not differentiated here (the pixel-boundary term, diff/pixel_boundary.h).
    template <typename T> T filter_weight(int x, int y, const Vec2<T>& s) const {
        const T p = rfilter->eval_normalized(Vec2<T>(s.x - T(x + 0.5f), s.y - T(y + 0.5f)));
        if (sample_border) return p;
        const float sx = detach(s.x), sy = detach(s.y);
        if (sx < 0.f || sy < 0.f || sx > float(width) || sy > float(height)) return T(0.f);
        return p / T(film_mass(x, y));
    }
    // F_j: the mass of pixel (x, y)'s normalized filter over the film [0, width] x [0, height].
    float film_mass(int x, int y) const;
    std::string to_string() const override;
};

} // namespace penumbra
