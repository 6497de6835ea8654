// Film (`hdrfilm`) and reconstruction filters (`box`, `tent`, `gaussian`) with Mitsuba 3's parameters.
//
// hdrfilm:
//   width, height     integer  768, 576  at most MaxFilmSide (65536) each
//   file_format       string   openexr   openexr | exr (the only output format)
//   pixel_format      string   rgb       luminance | luminance_alpha | rgb | rgba | xyz | xyza; EXR channels
//                                        Y, Y+A, R,G,B, R,G,B+A, X,Y,Z, X,Y,Z+A (alpha: the filtered fraction
//                                        of camera rays that hit a surface)
//   component_format  string   float16   float16 | float32 | uint32 (EXR storage; uint32 is normalized to
//                                        [0, 1] as Mitsuba's Bitmap does)
//   sample_border     boolean  false     true: edge pixels' filters also cover the plane beyond the film
//   banner            boolean  —         accepted and ignored (as Mitsuba 3 does)
//   crop_offset_x/y   integer  0, 0      top-left pixel of the crop window (the image) in the full frame
//   crop_width/height integer  the rest  size of the crop window (default: to the frame's right/bottom edge)
//   rfilter           nested   gaussian
// box:      radius 0.5 (fixed)                       f(x) = 1 for |x| < 1/2 (1/2 at |x| = 1/2)
// tent:     radius float 1                           f(x) = max(0, 1 - |x| / radius)
// gaussian: stddev float 0.5, radius = 4 stddev      f(x) = max(0, exp(-x^2 / (2 stddev^2)) - exp(-radius^2 /
// (2 stddev^2)))
#include "scene/film.h"

#include "scene/factory.h"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <sstream>

namespace penumbra {

// Bins of the tabulated 1D CDF used by sample(); the profile is piecewise constant on them.
static constexpr int FilterTableSize = 1024;


// Midpoint-rule tabulation of the profile on [-r, r]; the CDF is normalized so that cdf_.back() == 1.
void ReconstructionFilter::init_sampling() {
    cdf_.assign(FilterTableSize + 1, 0.f);
    const double h = 2.0 * radius_ / FilterTableSize;
    double sum = 0.0;
    for (int i = 0; i < FilterTableSize; ++i) {
        sum += std::max(0.f, eval(float(-radius_ + (i + 0.5) * h)));
        cdf_[i + 1] = float(sum);
    }
    for (float& c : cdf_)
        c = float(c / sum);
    cdf_.back() = 1.f;
    integral_ = float(sum * h);
    // Guide table: guide_[k] is the bin holding u = k / FilterTableSize, so inversion starts next to its answer.
    guide_.assign(FilterTableSize + 1, 0);
    int bin = 0;
    for (int k = 0; k <= FilterTableSize; ++k) {
        const float u = float(k) / FilterTableSize;
        while (bin < FilterTableSize - 1 && cdf_[bin + 1] <= u) ++bin;
        guide_[k] = bin;
    }
}

// Inverts the piecewise-linear CDF independently along x and y (the filter is separable).
Vec2f ReconstructionFilter::sample(const Vec2f& u) const {
    auto invert = [&](float ui) {
        int i = guide_[std::min(int(ui * FilterTableSize), FilterTableSize)];
        while (i < FilterTableSize - 1 && cdf_[i + 1] <= ui) ++i;
        const float width = cdf_[i + 1] - cdf_[i];
        const float t = width > 0.f ? (ui - cdf_[i]) / width : 0.5f;
        return -radius_ + (float(i) + std::clamp(t, 0.f, 1.f)) * (2.f * radius_ / FilterTableSize);
    };
    return {invert(u.x), invert(u.y)};
}

// The tabulated CDF at x: the bin holding x, then linear within it.
float ReconstructionFilter::cdf(float x) const {
    const float t = (x + radius_) / (2.f * radius_) * FilterTableSize;
    if (t <= 0.f) return 0.f;
    if (t >= FilterTableSize) return 1.f;
    const int i = int(t);
    return cdf_[i] + (cdf_[i + 1] - cdf_[i]) * (t - float(i));
}

// Truncated inversion: u is mapped to [F(lo), F(hi)] before the usual inversion, so the offset has density
// f / (F(hi) - F(lo)) on [lo, hi] (per axis).
Vec2f ReconstructionFilter::sample(const Vec2f& u, const Vec2f& lo, const Vec2f& hi) const {
    const float ax = cdf(lo.x), bx = cdf(hi.x), ay = cdf(lo.y), by = cdf(hi.y);
    const Vec2f offset = sample(Vec2f(ax + u.x * (bx - ax), ay + u.y * (by - ay)));
    return {std::clamp(offset.x, lo.x, hi.x), std::clamp(offset.y, lo.y, hi.y)};
}

// The pixel's filter is centred at (x + 1/2, y + 1/2); without sample_border its support is cut to the film
// [0, width] x [0, height], as Mitsuba's film samples only there and normalizes by the accumulated weights.
Vec2f Film::sample_position(int x, int y, const Vec2f& u) const {
    const Vec2f center(x + 0.5f, y + 0.5f);
    const Vec2f offset = sample_border
                             ? rfilter->sample(u)
                             : rfilter->sample(u, Vec2f(-center.x, -center.y),
                                               Vec2f(float(width) - center.x, float(height) - center.y));
    return center + offset;
}

// F_j = (F(W - c_x) - F(-c_x)) (F(H - c_y) - F(-c_y)) for the separable filter's 1D CDF F.
float Film::film_mass(int x, int y) const {
    const float cx = x + 0.5f, cy = y + 0.5f;
    return (rfilter->cdf(float(width) - cx) - rfilter->cdf(-cx)) *
           (rfilter->cdf(float(height) - cy) - rfilter->cdf(-cy));
}

std::string Film::to_string() const {
    std::ostringstream os;
    os << "HDRFilm[" << width << "x" << height;
    if (!(full_size == Vec2i(width, height)))
        os << " crop of " << full_size.x << "x" << full_size.y << " at (" << crop_offset.x << ", "
           << crop_offset.y << ")";
    os << ", rfilter=" << (rfilter ? rfilter->to_string() : "none") << "]";
    return os.str();
}

namespace {

class BoxFilter final : public FilterBase<BoxFilter> {
  public:
    BoxFilter() {
        radius_ = 0.5f;
        init_sampling();
    }
    // f = 1 inside, ½ exactly on the pixel's edge: a film position on the edge between two pixels counts half in
    // each (a splat there — a discontinuity lying exactly on a pixel edge, as in axis-aligned scenes seen head-on —
    // then gives the symmetric derivative, the one central differences converge to, instead of counting twice).
    template <typename T> T eval_t(const T& x) const {
        using std::abs;
        const float a = std::abs(detach(x));
        return T(a < radius_ ? 1.f : (a == radius_ ? 0.5f : 0.f));
    }
};

class TentFilter final : public FilterBase<TentFilter> {
  public:
    explicit TentFilter(float radius) {
        radius_ = radius;
        init_sampling();
    }
    template <typename T> T eval_t(const T& x) const {
        using std::abs;
        const T v = T(1.f) - abs(x) / T(radius_);
        return v > T(0.f) ? v : T(0.f);
    }
};

class GaussianFilter final : public FilterBase<GaussianFilter> {
  public:
    explicit GaussianFilter(float stddev) : alpha_(-1.f / (2.f * stddev * stddev)) {
        radius_ = 4.f * stddev;
        bias_ = std::exp(alpha_ * radius_ * radius_);
        init_sampling();
    }
    template <typename T> T eval_t(const T& x) const {
        using std::exp;
        const T v = exp(T(alpha_) * x * x) - T(bias_);
        return v > T(0.f) ? v : T(0.f);
    }

  private:
    float alpha_, bias_ = 0.f;
};

} // namespace

std::shared_ptr<Object> make_rfilter(const Properties& props, const LoadContext&) {
    const std::string& type = props.plugin();
    if (type == "box") return std::make_shared<BoxFilter>();
    if (type == "tent") {
        const float radius = props.get_float("radius", 1.f);
        if (!(radius > 0.f)) props.raise("radius", "radius must be positive");
        return std::make_shared<TentFilter>(radius);
    }
    if (type == "gaussian") {
        const float stddev = props.get_float("stddev", 0.5f);
        if (!(stddev > 0.f)) props.raise("stddev", "stddev must be positive");
        return std::make_shared<GaussianFilter>(stddev);
    }
    throw_unsupported_plugin(props, ObjectKind::RFilter);
}

std::shared_ptr<Object> make_film(const Properties& props, const LoadContext& ctx) {
    if (props.plugin() != "hdrfilm") throw_unsupported_plugin(props, ObjectKind::Film);
    auto film = std::make_shared<Film>();
    // Sizes and offsets are checked as the 64-bit integers they are parsed as, before they are narrowed to
    // int (a width of 2^32 + 10 must not become 10, nor crop_offset_x + crop_width overflow).
    auto film_int = [&](const char* name, int64_t def, int64_t lo) {
        const int64_t v = props.get_int(name, def);
        if (v < lo || v > MaxFilmSide)
            props.raise(name, std::string(name) + " must be in [" + std::to_string(lo) + ", " +
                                  std::to_string(MaxFilmSide) + "], got " + std::to_string(v));
        return int(v);
    };
    film->width = film_int("width", 768, 1);
    film->height = film_int("height", 576, 1);

    // Index of the value in `allowed` (case-insensitive, as Mitsuba lowercases these strings).
    auto check_choice = [&](const char* name, const char* def, std::initializer_list<const char*> allowed) {
        std::string value = props.get_string(name, def);
        std::transform(value.begin(), value.end(), value.begin(),
                       [](unsigned char c) { return char(std::tolower(c)); });
        std::string list;
        int index = 0;
        for (const char* a : allowed) {
            if (value == a) return index;
            ++index;
            list += std::string(list.empty() ? "'" : ", '") + a + "'";
        }
        props.raise(name, std::string("invalid ") + name + " '" + value + "' (expected " + list + ")");
    };
    check_choice("file_format", "openexr", {"openexr", "exr"});
    using PF = Film::PixelFormat;
    film->pixel_format = PF(
        check_choice("pixel_format", "rgb", {"luminance", "luminance_alpha", "rgb", "rgba", "xyz", "xyza"}));
    film->component_format =
        ComponentFormat(check_choice("component_format", "float16", {"float16", "float32", "uint32"}));
    film->sample_border = props.get_bool("sample_border", false);
    if (props.has("banner")) props.get_bool("banner", true);
    // Mitsuba's Film: the crop window must lie inside the full frame.
    film->full_size = Vec2i(film->width, film->height);
    film->crop_offset = Vec2i(film_int("crop_offset_x", 0, 0), film_int("crop_offset_y", 0, 0));
    film->width = film_int("crop_width", std::max(film->full_size.x - film->crop_offset.x, 1), 1);
    film->height = film_int("crop_height", std::max(film->full_size.y - film->crop_offset.y, 1), 1);
    if (film->crop_offset.x < 0 || film->crop_offset.x >= film->full_size.x)
        props.raise("crop_offset_x", "crop_offset_x must be in [0, width)");
    if (film->crop_offset.y < 0 || film->crop_offset.y >= film->full_size.y)
        props.raise("crop_offset_y", "crop_offset_y must be in [0, height)");
    if (film->width <= 0 || film->crop_offset.x + film->width > film->full_size.x)
        props.raise("crop_width", "crop_width must be positive and crop_offset_x + crop_width at most width");
    if (film->height <= 0 || film->crop_offset.y + film->height > film->full_size.y)
        props.raise("crop_height",
                    "crop_height must be positive and crop_offset_y + crop_height at most height");

    const auto filters = props.objects(ObjectKind::RFilter);
    if (filters.size() > 1) throw LoadError(filters[1]->location, "hdrfilm: more than one rfilter given");
    if (filters.empty()) {
        film->rfilter = std::static_pointer_cast<ReconstructionFilter>(
            make_rfilter(Properties("gaussian", props.location()), ctx));
        film->rfilter->plugin = "gaussian";
        film->rfilter->location = props.location();
    } else {
        film->rfilter = std::static_pointer_cast<ReconstructionFilter>(filters[0]);
    }
    return film;
}

} // namespace penumbra
