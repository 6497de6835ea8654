// Mitsuba 3 `checkerboard` texture.
//
// Parameters:
//   color0  texture/rgb/float  0.4   value of the patches where both fractional uv parts are on the same
//                                    side of 1/2
//   color1  texture/rgb/float  0.2   value of the other patches
//   to_uv   transform          none  affine map applied to the uv coordinates first
#include "scene/textures/textures.h"

#include <cmath>

namespace penumbra {

namespace {

class CheckerboardTexture final : public TextureBase<CheckerboardTexture> {
  public:
    CheckerboardTexture(std::shared_ptr<Texture> c0, std::shared_ptr<Texture> c1,
                        const std::array<float, 6>& to_uv)
        : color0_(std::move(c0)), color1_(std::move(c1)), to_uv_(to_uv) {}

    // Mitsuba's rule: with (u, v) = to_uv(uv), color0 where (frac(u) > 1/2) == (frac(v) > 1/2), else color1.
    template <typename T> Color3<T> eval_t(const SurfaceInteraction<T>& si) const {
        const float u = to_uv_[0] * detach(si.uv.x) + to_uv_[1] * detach(si.uv.y) + to_uv_[2];
        const float v = to_uv_[3] * detach(si.uv.x) + to_uv_[4] * detach(si.uv.y) + to_uv_[5];
        const bool mu = u - std::floor(u) > 0.5f, mv = v - std::floor(v) > 0.5f;
        return mu == mv ? color0_->eval(si) : color1_->eval(si);
    }
    Color3f mean() const override { return (color0_->mean() + color1_->mean()) * 0.5f; }
    bool is_continuous() const override { return false; }

  private:
    std::shared_ptr<Texture> color0_, color1_;
    std::array<float, 6> to_uv_;
};

} // namespace

std::shared_ptr<Texture> make_checkerboard_texture(const Properties& props) {
    auto c0 = props.get_texture("color0", Color3f(0.4f));
    auto c1 = props.get_texture("color1", Color3f(0.2f));
    return std::make_shared<CheckerboardTexture>(std::move(c0), std::move(c1),
                                                 uv_affine(props.get_transform("to_uv")));
}

} // namespace penumbra
