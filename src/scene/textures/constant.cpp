// Constant texture: what rgb/spectrum/float parameters become, and Mitsuba's `srgb` / `uniform` texture
// plugins.
//
// Mitsuba parameters (via make_texture):
//   srgb:        color  rgb           (required)
//   uniform:     value  float         (required)
//   rawconstant: value  float|vector  (required)  used as is (no color conversion)
#include "core/param.h"
#include "scene/textures/textures.h"

namespace penumbra {

namespace {

class ConstantTexture final : public TextureBase<ConstantTexture> {
  public:
    explicit ConstantTexture(const Color3f& value) : value_(value) {}
    template <typename T> Color3<T> eval_t(const SurfaceInteraction<T>&) const {
        return param_color<T>(value_, index_);
    }
    // Mitsuba's srgb, uniform and rawconstant textures all name their value `value`.
    void traverse(ParamVisitor& v) override { v.put("value", &value_.x, 3, &index_); }
    Color3f mean() const override { return value_; }
    bool is_constant() const override { return true; }
    std::string to_string() const override {
        return "ConstantTexture[" + std::to_string(value_.x) + ", " + std::to_string(value_.y) + ", " +
               std::to_string(value_.z) + "]";
    }

  private:
    Color3f value_;
    int index_ = -1;
};

} // namespace

std::shared_ptr<Texture> make_constant_texture(const Color3f& value) {
    return std::make_shared<ConstantTexture>(value);
}

std::shared_ptr<Texture> make_srgb_texture(const Properties& props) {
    return make_constant_texture(props.get_color("color"));
}

std::shared_ptr<Texture> make_uniform_texture(const Properties& props) {
    return make_constant_texture(Color3f(props.get_float("value")));
}

std::shared_ptr<Texture> make_rawconstant_texture(const Properties& props) {
    const Properties::Tag tag = props.type("value");
    if (tag != Properties::Tag::Float && tag != Properties::Tag::Vector)
        props.raise("value", "rawconstant: 'value' must be a float or a vector");
    const Color3f value =
        tag == Properties::Tag::Float ? Color3f(props.get_float("value")) : props.get_vector("value");
    return make_constant_texture(value);
}

} // namespace penumbra
