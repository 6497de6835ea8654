// Film (hdrfilm) and pixel reconstruction filters (box, tent, gaussian) with Mitsuba 3's parameters.
#pragma once
#include "scene/object.h"
#include "core/vector.h"

#include <memory>
#include <vector>

namespace penumbra {

class ReconstructionFilter : public Object {
public:
    ObjectKind kind() const override { return ObjectKind::RFilter; }
    float radius() const { return radius_; }
    // Separable 1D filter profile (not normalized), zero beyond radius().
    virtual float eval(float x) const = 0;
    // 2D filter value f(x) f(y) normalized to integrate to 1 over the plane.
    float eval_normalized(const Vec2f& offset) const;
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

class Film : public Object {
public:
    ObjectKind kind() const override { return ObjectKind::Film; }
    int width = 768, height = 576;
    std::shared_ptr<ReconstructionFilter> rfilter;
    std::string to_string() const override;
};

} // namespace penumbra
