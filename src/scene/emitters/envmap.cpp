// Environment map (Mitsuba 3 `envmap`): radiance at infinity from a latitude-longitude image.
//
// | name             | type      | default  | meaning                                                    |
// |------------------|-----------|----------|------------------------------------------------------------|
// | filename         | string    | required | EXR/HDR/PNG/... lat-long image of radiance                 |
// | scale            | float     | 1        | factor applied to the image values                         |
// | to_world         | transform | identity | emitter-to-world transform                                 |
// | mis_compensation | bool      | false    | subtract the mean luminance from the sampling density      |
//
// Mitsuba 3's lat-long convention (local frame): +y is up; u = atan2(x, -z) / (2 pi), so u = 0 looks along -z
// and u grows toward +x; theta = v pi is measured from +y:
//     d(u, v) = (sin(phi) sin(theta), cos(theta), -cos(phi) sin(theta)),  phi = 2 pi u, theta = pi v.
// Pixel (x, y) of a W x H image sits at u = (x + 1/2) / W (column centers, periodic in u) and v = y / (H - 1)
// (the first row is the +y pole, the last row the -y pole); radiance is bilinear between these samples.
//
// Sampling: a piecewise-constant Distribution2D over the W x (H-1) cells of that bilinear grid, each weighted by
// the mean luminance of its 4 corners times sin(theta) at its center. A cell is sampled whenever any corner is
// non-zero, so every direction with non-zero radiance has non-zero density. Mitsuba uses a piecewise-bilinear
// warp instead; both are unbiased. Solid-angle pdf = pdf_uv / (2 pi^2 sin(theta)).
#include "core/distribution.h"
#include "core/image.h"
#include "core/param.h"
#include "core/warp.h"
#include "scene/emitters/emitters.h"

#include <memory>
#include <sstream>

namespace penumbra {

namespace {

constexpr float TwoPiSquared = 2.f * Pi * Pi;
constexpr float MinSinTheta = 1e-7f;

class EnvmapEmitter final : public EmitterBase<EnvmapEmitter> {
public:
    EnvmapEmitter(Image image, float scale, const Transform& to_world, bool mis_compensation)
        : image_(std::move(image)), scale_(scale), to_world_(to_world), to_local_(to_world.inverse()) {
        flags_ = EmitterInfinite;
        scene_bounds_ = {Vec3f(0.f), 1.f}; // Mitsuba's unit sphere until the scene is known
        build_distribution(mis_compensation);
    }

    // Mitsuba enlarges the scene's bounding sphere by a relative RayEpsilon.
    void set_scene_bounds(const BoundingSphere& b) override {
        Emitter::set_scene_bounds({b.center, std::max(RayEpsilon, b.radius * (1.f + RayEpsilon))});
    }

    std::pair<DirectionSample3f, Color3f> sample_direction(const Interaction3f& ref, const Vec2f& u) const override {
        DirectionSample3f ds;
        ds.emitter = this;
        ds.delta = false;
        float pdf_uv = 0.f;
        Vec2f uv;
        if (!sample_uv(u, uv, pdf_uv)) return {ds, Color3f(0.f)};
        float sin_theta;
        ds.d = normalize(to_world_.apply_vector(uv_to_direction(uv, sin_theta)));
        ds.pdf = pdf_uv / (TwoPiSquared * sin_theta);
        const float radius = std::max(scene_bounds_.radius, norm(ref.p - scene_bounds_.center));
        ds.dist = 2.f * radius;
        ds.p = ref.p + ds.d * ds.dist;
        ds.n = -ds.d;
        ds.uv = uv;
        return {ds, lookup<float>(uv.x, uv.y) / ds.pdf};
    }

    // Direction toward the environment by importance, origin uniform on the disk of the bounding sphere
    // perpendicular to it (pdf 1/(pi r^2)) on the environment's side: weight = pi r^2 L / pdf_dir.
    std::pair<Ray, Color3f> sample_ray(const Vec2f& u_position, const Vec2f& u_direction) const override {
        float pdf_uv = 0.f;
        Vec2f uv;
        if (!sample_uv(u_direction, uv, pdf_uv)) return {Ray(), Color3f(0.f)};
        float sin_theta;
        const Vec3f to_env = normalize(to_world_.apply_vector(uv_to_direction(uv, sin_theta)));
        const float pdf_dir = pdf_uv / (TwoPiSquared * sin_theta);
        const Vec2f offset = warp::square_to_uniform_disk_concentric(u_position);
        const Vec3f perpendicular = Frame3f(to_env).to_world(Vec3f(offset.x, offset.y, 0.f));
        const float r = scene_bounds_.radius;
        const Vec3f origin = scene_bounds_.center + (perpendicular + to_env) * r;
        return {Ray(origin, -to_env), lookup<float>(uv.x, uv.y) * (Pi * r * r / pdf_dir)};
    }

    template <typename T> T pdf_direction_t(const Interaction<T>&, const DirectionSample<T>& ds) const {
        using std::sqrt;
        if (distribution_.empty()) return T(0);
        const Vec3<T> v = normalize(to_local_.apply_vector(ds.d));
        const Vec2<T> uv = direction_to_uv(v);
        float su = detach(uv.x) - half_texel();
        su -= std::floor(su);
        const float pdf_uv = distribution_.pdf(Vec2f(su, detach(uv.y)));
        const T sin_theta = sqrt(v.x * v.x + v.z * v.z);
        return T(pdf_uv) / (T(TwoPiSquared) * (sin_theta > T(MinSinTheta) ? sin_theta : T(MinSinTheta)));
    }

    template <typename T> Color3<T> eval_t(const SurfaceInteraction<T>&) const { return Color3<T>(T(0)); }

    // Radiance arriving along an escaped ray of world direction d: bilinear lookup at d's (u, v).
    template <typename T> Color3<T> eval_environment_t(const Vec3<T>& d) const {
        const Vec2<T> uv = direction_to_uv(normalize(to_local_.apply_vector(d)));
        return lookup<T>(uv.x, uv.y);
    }

    // Power entering the bounding sphere: pi r^2 * int L dw (midpoint rule over the bilinear cells).
    Color3f power() const override {
        const int w = image_.width, h = image_.height;
        Color3f integral(0.f);
        for (int j = 0; j + 1 < h; ++j) {
            const float sin_theta = std::sin((j + 0.5f) * Pi / float(h - 1));
            for (int i = 0; i < w; ++i) integral += corner_mean(i, j) * sin_theta;
        }
        integral *= scale_ * (2.f * Pi / float(w)) * (Pi / float(h - 1));
        const float r = scene_bounds_.radius;
        return integral * (Pi * r * r);
    }

    // Mitsuba's keys. The sampling density stays the one built at load time: estimates stay unbiased as long
    // as the radiance is zero wherever that density is.
    void traverse(ParamVisitor& v) override {
        v.put("scale", &scale_, 1, &scale_index_);
        v.put_array("data", &image_.pixels[0].x, {image_.height, image_.width, 3}, &data_index_);
    }

    bool movable() const override { return true; }
    Transform to_world() const override { return to_world_; }
    void set_to_world(const Transform& t) override {
        to_world_ = t;
        to_local_ = t.inverse();
    }

    std::string to_string() const override {
        std::ostringstream os;
        os << "EnvmapEmitter[resolution = " << image_.width << "x" << image_.height << ", scale = " << scale_ << "]";
        return os.str();
    }

private:
    float half_texel() const { return 0.5f / float(image_.width); }

    // Inverse of uv_to_direction for a unit local direction.
    template <typename T> static Vec2<T> direction_to_uv(const Vec3<T>& v) {
        using std::acos;
        using std::atan2;
        const T y = v.y > T(1) ? T(1) : (v.y < T(-1) ? T(-1) : v.y);
        return {atan2(v.x, -v.z) * T(Inv2Pi), acos(y) * T(InvPi)};
    }

    static Vec3f uv_to_direction(const Vec2f& uv, float& sin_theta) {
        const float theta = uv.y * Pi, phi = uv.x * 2.f * Pi;
        const float st = std::sin(theta);
        sin_theta = std::max(st, MinSinTheta);
        return {std::sin(phi) * st, std::cos(theta), -std::cos(phi) * st};
    }

    // Samples (u, v) from the cell distribution, shifted by half a texel so that cells span pixel centers.
    bool sample_uv(const Vec2f& u, Vec2f& uv, float& pdf_uv) const {
        if (distribution_.empty()) return false;
        const Vec2f s = distribution_.sample(u, pdf_uv);
        uv = Vec2f(s.x + half_texel(), s.y);
        return pdf_uv > 0.f;
    }

    const Color3f& pixel(int x, int y) const { return image_.at(x % image_.width, y); }
    // A pixel as a parameter (`data`: 3 values per pixel, row by row).
    template <typename T> Color3<T> texel(int x, int y) const {
        const int i = y * image_.width + x % image_.width;
        return param_color<T>(image_.pixels[size_t(i)], data_index_ < 0 ? -1 : data_index_ + 3 * i);
    }
    Color3f corner_mean(int i, int j) const {
        return (pixel(i, j) + pixel(i + 1, j) + pixel(i, j + 1) + pixel(i + 1, j + 1)) * 0.25f;
    }

    // Bilinear interpolation between pixel samples at u = (x + 1/2)/W (periodic) and v = y/(H-1), times scale.
    template <typename T> Color3<T> lookup(const T& u, const T& v) const {
        using std::floor;
        const int w = image_.width, h = image_.height;
        T x = u - T(half_texel());
        x = (x - floor(x)) * T(float(w));
        const T y = v * T(float(h - 1));
        const int ix = std::clamp(int(detach(x)), 0, w - 1);
        const int iy = std::clamp(int(detach(y)), 0, h - 2);
        const T fx = x - T(float(ix)), fy = y - T(float(iy));
        const Color3<T> c0 = texel<T>(ix, iy) * (T(1) - fx) + texel<T>(ix + 1, iy) * fx;
        const Color3<T> c1 = texel<T>(ix, iy + 1) * (T(1) - fx) + texel<T>(ix + 1, iy + 1) * fx;
        return (c0 * (T(1) - fy) + c1 * fy) * param_value<T>(scale_, scale_index_);
    }

    // Cell weights: mean corner luminance (minus the MIS-compensation offset) times sin(theta) at the cell center.
    void build_distribution(bool mis_compensation) {
        const int w = image_.width, h = image_.height;
        std::vector<float> lum(size_t(w) * h);
        double lum_sum = 0.0;
        float lum_min = Infinity;
        for (int y = 0; y < h; ++y)
            for (int x = 0; x < w; ++x) {
                const float l = std::max(luminance(image_.at(x, y)), 0.f);
                lum[size_t(y) * w + x] = l;
                lum_sum += l;
                lum_min = std::min(lum_min, l);
            }
        // Karlik et al. 2019, "MIS compensation": sample max(L - mean(L), 0); disabled for near-constant maps.
        const float mean = float(lum_sum / (double(w) * h));
        const float offset = mis_compensation && mean - lum_min > 0.01f * mean ? mean : 0.f;
        auto l = [&](int x, int y) { return std::max(lum[size_t(y) * w + x % w] - offset, 0.f); };
        std::vector<float> cells(size_t(w) * (h - 1));
        double total = 0.0;
        for (int j = 0; j + 1 < h; ++j) {
            const float sin_theta = std::sin((j + 0.5f) * Pi / float(h - 1));
            for (int i = 0; i < w; ++i) {
                const float c = 0.25f * (l(i, j) + l(i + 1, j) + l(i, j + 1) + l(i + 1, j + 1)) * sin_theta;
                cells[size_t(j) * w + i] = c;
                total += c;
            }
        }
        if (total > 0.0) distribution_ = Distribution2D(cells, w, h - 1); // an all-black map is never sampled
    }

    Image image_;
    float scale_;
    int scale_index_ = -1, data_index_ = -1;
    Transform to_world_, to_local_;
    Distribution2D distribution_;
};

} // namespace

std::shared_ptr<Emitter> make_envmap_emitter(Image image, float scale, const Transform& to_world,
                                             bool mis_compensation) {
    if (image.width < 2 || image.height < 3)
        throw Error("the environment map resolution must be at least 2x3 pixels, got " + std::to_string(image.width) +
                    "x" + std::to_string(image.height));
    for (int y = 0; y < image.height; ++y)
        for (int x = 0; x < image.width; ++x) {
            const Color3f& c = image.at(x, y);
            if (!is_finite(c) || c.x < 0.f || c.y < 0.f || c.z < 0.f)
                throw Error("the environment map has a negative or non-finite pixel at (" + std::to_string(x) + ", " +
                            std::to_string(y) + ")");
        }
    return std::make_shared<EnvmapEmitter>(std::move(image), scale, to_world, mis_compensation);
}

std::shared_ptr<Emitter> make_envmap_emitter(const Properties& props, const LoadContext& ctx) {
    const std::string filename = props.get_string("filename");
    const float scale = props.get_float("scale", 1.f);
    if (!std::isfinite(scale) || scale < 0.f) props.raise("scale", "'scale' must be finite and non-negative");
    const Transform to_world = props.get_transform("to_world");
    const bool mis_compensation = props.get_bool("mis_compensation", false);
    const std::string path = ctx.resolve(filename, props.location("filename"));
    try {
        return make_envmap_emitter(read_image(path, true), scale, to_world, mis_compensation);
    } catch (const LoadError&) {
        throw;
    } catch (const Error& e) {
        props.raise("filename", "'" + filename + "': " + e.what());
    }
}

} // namespace penumbra
