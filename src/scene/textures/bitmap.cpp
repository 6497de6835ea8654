// Mitsuba 3 `bitmap` texture.
//
// Parameters:
//   filename     string     (required)  EXR (linear), PNG/JPEG/BMP/TGA (sRGB unless raw), HDR (linear)
//   filter_type  string     bilinear    bilinear | nearest
//   wrap_mode    string     repeat      repeat | mirror | clamp
//   raw          boolean    false       true: keep 8-bit values as stored (no sRGB -> linear decoding)
//   to_uv        transform  none        affine map applied to the uv coordinates first
//   format       string     auto        auto | variant | fp16: fp16 rounds the texels to half precision; auto and
//                                       variant keep float32 (Mitsuba's auto stores <= 16-bit sources as
//                                       half, a rounding of at most 2^-11 relative that penumbra does not
//                                       reproduce)
//   accel        boolean    true        accepted; it selects CUDA texture hardware in Mitsuba, nothing on the CPU
//
// traverse(): `data`, the texels (linear RGB, row-major from the top row), differentiable.
//
// Uv convention (as Mitsuba): (u, v) = (0, 0) is the top-left corner of the image, u to the right, v down;
// texel (i, j) covers [i, i+1]/W x [j, j+1]/H. Mitsuba's mesh loaders flip v (v = 1 - v_obj) so that OBJ uvs,
// whose v points up, address the image the usual way.
#include "core/image.h"
#include "core/param.h"
#include "scene/textures/textures.h"

#include <Imath/half.h>

#include <cmath>

namespace penumbra {

namespace {

enum class WrapMode { Repeat, Mirror, Clamp };

class BitmapTexture final : public TextureBase<BitmapTexture> {
  public:
    BitmapTexture(Image image, bool bilinear, WrapMode wrap, const std::array<float, 6>& to_uv,
                  std::string name)
        : image_(std::move(image)), bilinear_(bilinear), wrap_(wrap), to_uv_(to_uv), name_(std::move(name)) {
        Vec3d sum(0.0);
        for (const Color3f& c : image_.pixels)
            sum += Vec3d(c);
        mean_ = Color3f(sum / double(image_.pixels.size()));
    }

    // The four texels around texture position (u W - 1/2, v H - 1/2), (u, v) = to_uv(si.uv), and the
    // bilinear weights toward the second of each pair (differentiable in uv).
    template <typename T> struct Bilinear {
        int xa, xb, ya, yb;
        T wx, wy;
    };
    template <typename T> Vec2<T> texture_uv(const SurfaceInteraction<T>& si) const {
        return {si.uv.x * to_uv_[0] + si.uv.y * to_uv_[1] + T(to_uv_[2]),
                si.uv.x * to_uv_[3] + si.uv.y * to_uv_[4] + T(to_uv_[5])};
    }
    template <typename T> Bilinear<T> bilinear(const Vec2<T>& uv) const {
        const int w = image_.width, h = image_.height;
        const T px = uv.x * float(w) - T(0.5f), py = uv.y * float(h) - T(0.5f);
        const int x0 = int(std::floor(detach(px))), y0 = int(std::floor(detach(py)));
        return {wrap(x0, w),     wrap(x0 + 1, w),   wrap(y0, h),
                wrap(y0 + 1, h), px - T(float(x0)), py - T(float(y0))};
    }

    // Bilinear: f(u W - 1/2, v H - 1/2) interpolated between the four nearest texel centers; nearest: the
    // texel containing (u W, v H). Derivatives flow through the interpolation weights and, when `data` is
    // differentiated, through the texel values.
    template <typename T> Color3<T> eval_t(const SurfaceInteraction<T>& si) const {
        const Vec2<T> uv = texture_uv(si);
        if (!bilinear_) {
            const int w = image_.width, h = image_.height;
            const int x = wrap(int(std::floor(detach(uv.x) * float(w))), w);
            const int y = wrap(int(std::floor(detach(uv.y) * float(h))), h);
            return texel<T>(x, y);
        }
        const Bilinear<T> b = bilinear(uv);
        const Color3<T> top = texel<T>(b.xa, b.ya) * (T(1.f) - b.wx) + texel<T>(b.xb, b.ya) * b.wx;
        const Color3<T> bottom = texel<T>(b.xa, b.yb) * (T(1.f) - b.wx) + texel<T>(b.xb, b.yb) * b.wx;
        return top * (T(1.f) - b.wy) + bottom * b.wy;
    }

    // Single-channel value: the luminance of the texel color, as Mitsuba's bitmap eval_1 (a gray bitmap gives its
    // value: the weights sum to 1).
#define PENUMBRA_BITMAP_EVAL_1(T)                                                                            \
    T eval_1(const SurfaceInteraction<T>& si) const override { return luminance(eval_t<T>(si)); }
    PENUMBRA_FOR_EACH_SCALAR(PENUMBRA_BITMAP_EVAL_1)
#undef PENUMBRA_BITMAP_EVAL_1

    // d eval_1 / d(u, v) of the bilinear interpolant (zero for nearest: piecewise constant), with eval_1 the
    // luminance: d/du = W [(f10 - f00)(1 - wy) + (f11 - f01) wy],
    //               d/dv = H [(f01 - f00)(1 - wx) + (f11 - f10) wx], chained through the to_uv map.
    template <typename T> Vec2<T> eval_1_grad_t(const SurfaceInteraction<T>& si) const {
        if (!bilinear_) return Vec2<T>(T(0), T(0));
        const Bilinear<T> b = bilinear(texture_uv(si));
        const T f00 = luminance(texel<T>(b.xa, b.ya)), f10 = luminance(texel<T>(b.xb, b.ya));
        const T f01 = luminance(texel<T>(b.xa, b.yb)), f11 = luminance(texel<T>(b.xb, b.yb));
        const T d_du = ((f10 - f00) * (T(1.f) - b.wy) + (f11 - f01) * b.wy) * float(image_.width);
        const T d_dv = ((f01 - f00) * (T(1.f) - b.wx) + (f11 - f10) * b.wx) * float(image_.height);
        return {d_du * to_uv_[0] + d_dv * to_uv_[3], d_du * to_uv_[1] + d_dv * to_uv_[4]};
    }
#define PENUMBRA_BITMAP_GRAD(T)                                                                              \
    Vec2<T> eval_1_grad(const SurfaceInteraction<T>& si) const override { return eval_1_grad_t<T>(si); }
    PENUMBRA_FOR_EACH_SCALAR(PENUMBRA_BITMAP_GRAD)
#undef PENUMBRA_BITMAP_GRAD

    void traverse(ParamVisitor& v) override {
        v.put_array("data", &image_.pixels[0].x, {image_.height, image_.width, 3}, &index_);
    }

    Color3f mean() const override { return mean_; }
    bool is_continuous() const override { return bilinear_; }
    Vec2i resolution() const override { return {image_.width, image_.height}; }
    std::string to_string() const override {
        return "BitmapTexture[" + name_ + ", " + std::to_string(image_.width) + "x" +
               std::to_string(image_.height) + "]";
    }

  private:
    // Texel (x, y) as stored, or as parameters 3 (y W + x) .. + 2 of `data` when it is differentiated.
    template <typename T> Color3<T> texel(int x, int y) const {
        const int i = index_ < 0 ? -1 : index_ + 3 * (y * image_.width + x);
        return param_color<T>(image_.at(x, y), i);
    }
    // Maps an integer texel index into [0, n) according to the wrap mode (mirror has period 2n: ... 1 0 | 0 1
    // ...).
    int wrap(int i, int n) const {
        switch (wrap_) {
        case WrapMode::Clamp:
            return std::clamp(i, 0, n - 1);
        case WrapMode::Repeat:
            return ((i % n) + n) % n;
        case WrapMode::Mirror: {
            const int p = ((i % (2 * n)) + 2 * n) % (2 * n);
            return p < n ? p : 2 * n - 1 - p;
        }
        }
        return i;
    }

    Image image_;
    bool bilinear_;
    WrapMode wrap_;
    std::array<float, 6> to_uv_;
    std::string name_;
    Color3f mean_;
    int index_ = -1;
};

} // namespace

std::shared_ptr<Texture> make_bitmap_texture(const Properties& props, const LoadContext& ctx) {
    const std::string filename = props.get_string("filename");
    const std::string path = ctx.resolve(filename, props.location("filename"));

    const std::string filter = props.get_string("filter_type", "bilinear");
    if (filter != "bilinear" && filter != "nearest")
        props.raise("filter_type", "invalid filter_type '" + filter + "' (expected 'bilinear' or 'nearest')");

    const std::string wrap_name = props.get_string("wrap_mode", "repeat");
    WrapMode wrap;
    if (wrap_name == "repeat")
        wrap = WrapMode::Repeat;
    else if (wrap_name == "mirror")
        wrap = WrapMode::Mirror;
    else if (wrap_name == "clamp")
        wrap = WrapMode::Clamp;
    else
        props.raise("wrap_mode",
                    "invalid wrap_mode '" + wrap_name + "' (expected 'repeat', 'mirror' or 'clamp')");

    const std::string format = props.get_string("format", "auto");
    if (format != "auto" && format != "variant" && format != "fp16")
        props.raise("format", "invalid format '" + format + "' (expected 'auto', 'variant' or 'fp16')");
    props.get_bool("accel", true);

    const bool raw = props.get_bool("raw", false);
    const auto to_uv = uv_affine(props.get_transform("to_uv"));
    Image image;
    try {
        image = read_image(path, !raw);
    } catch (const Error& e) {
        throw LoadError(props.location("filename"), e.what());
    }
    if (image.pixels.empty()) props.raise("filename", "image '" + path + "' is empty");
    if (format == "fp16")
        for (Color3f& c : image.pixels)
            for (int k = 0; k < 3; ++k)
                c[k] = float(half(c[k]));
    return std::make_shared<BitmapTexture>(std::move(image), filter == "bilinear", wrap, to_uv, filename);
}

} // namespace penumbra
