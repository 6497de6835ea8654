#include "core/plot.h"

#include "core/error.h"

#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wunused-function"
#include <stb/stb_easy_font.h>
#pragma GCC diagnostic pop

#include <algorithm>
#include <cmath>
#include <cstdio>

namespace penumbra {

namespace {

// sRGB 8-bit colors, converted to the linear values an Image holds (write_image encodes them back).
Color3f srgb(int r, int g, int b) {
    return Color3f(srgb_to_linear(r / 255.f), srgb_to_linear(g / 255.f), srgb_to_linear(b / 255.f));
}

// Tableau-10 palette (matplotlib's default cycle).
Color3f palette(size_t i) {
    static const int rgb[][3] = {{31, 119, 180},  {255, 127, 14}, {44, 160, 44},   {214, 39, 40},
                                 {148, 103, 189}, {140, 86, 75},  {227, 119, 194}, {127, 127, 127},
                                 {188, 189, 34},  {23, 190, 207}};
    const int* c = rgb[i % 10];
    return srgb(c[0], c[1], c[2]);
}

// stb_easy_font takes a mutable C string of printable ASCII; anything else is drawn as '?'.
std::vector<char> easy_font_text(const std::string& s) {
    std::vector<char> chars;
    for (char c : s)
        chars.push_back(c >= 32 && c < 127 ? c : '?');
    chars.push_back('\0');
    return chars;
}

class Canvas {
  public:
    explicit Canvas(Image& image) : image_(image) {}

    void blend(int x, int y, const Color3f& c, float coverage) {
        if (x < 0 || y < 0 || x >= image_.width || y >= image_.height || coverage <= 0.f) return;
        Color3f& p = image_.at(x, y);
        p = p * (1.f - coverage) + c * coverage;
    }

    void fill_rect(int x0, int y0, int x1, int y1, const Color3f& c) {
        for (int y = std::max(y0, 0); y < std::min(y1, image_.height); ++y)
            for (int x = std::max(x0, 0); x < std::min(x1, image_.width); ++x)
                image_.at(x, y) = c;
    }

    // Anti-aliased segment of the given width: pixel coverage = clamp(w/2 + 1/2 − distance to the segment).
    void line(double x0, double y0, double x1, double y1, float width, const Color3f& c) {
        const double r = width * 0.5 + 1.0;
        const double dx = x1 - x0, dy = y1 - y0, len2 = dx * dx + dy * dy;
        for (int y = int(std::floor(std::min(y0, y1) - r)); y <= int(std::ceil(std::max(y0, y1) + r)); ++y)
            for (int x = int(std::floor(std::min(x0, x1) - r)); x <= int(std::ceil(std::max(x0, x1) + r));
                 ++x) {
                const double px = x + 0.5 - x0, py = y + 0.5 - y0;
                const double t = len2 > 0 ? std::clamp((px * dx + py * dy) / len2, 0.0, 1.0) : 0.0;
                const double d = std::hypot(px - t * dx, py - t * dy);
                blend(x, y, c, float(std::clamp(width * 0.5 + 0.5 - d, 0.0, 1.0)));
            }
    }

    // Text with its top-left corner at (x, y), glyphs scaled by an integer factor. Rotated text reads bottom
    // to top with (x, y) its bottom-left corner.
    void text(int x, int y, const std::string& s, int scale, const Color3f& c, bool rotated = false) {
        std::vector<char> chars = easy_font_text(s);
        std::vector<char> buffer(chars.size() * 1200 + 1024); // ≤ ~70 quads of 4 × 16-byte vertices per glyph
        const int quads =
            stb_easy_font_print(0.f, 0.f, chars.data(), nullptr, buffer.data(), int(buffer.size()));
        for (int q = 0; q < quads; ++q) {
            const float* v0 = reinterpret_cast<const float*>(buffer.data() + size_t(q) * 64);
            const float* v2 = reinterpret_cast<const float*>(buffer.data() + size_t(q) * 64 + 32);
            const int u0 = int(v0[0]) * scale, w0 = int(v0[1]) * scale, u1 = int(v2[0]) * scale,
                      w1 = int(v2[1]) * scale;
            if (rotated)
                fill_rect(x + w0, y - u1, x + w1, y - u0, c);
            else
                fill_rect(x + u0, y + w0, x + u1, y + w1, c);
        }
    }

  private:
    Image& image_;
};

int text_width(const std::string& s, int scale) {
    std::vector<char> chars = easy_font_text(s);
    return stb_easy_font_width(chars.data()) * scale;
}
constexpr int GlyphHeight = 7; // stb_easy_font capitals are 7 units tall

std::string format_tick(double v) {
    char buf[32];
    std::snprintf(buf, sizeof(buf), "%g", std::abs(v) < 1e-12 ? 0.0 : v);
    return buf;
}

struct Axis {
    double lo = 0, hi = 1;     // in plotted units (log10 y for a log axis)
    std::vector<double> ticks; // in plotted units
    bool log = false;
};

// Linear axis: a "nice" step of 1, 2 or 5 × 10^k giving about five intervals, range snapped to it.
Axis linear_axis(double lo, double hi) {
    if (!(hi > lo)) {
        const double pad = lo == 0 ? 1.0 : std::abs(lo) * 0.5;
        lo -= pad;
        hi += pad;
    }
    const double raw = (hi - lo) / 5.0, mag = std::pow(10.0, std::floor(std::log10(raw))), n = raw / mag;
    const double step = (n < 1.5 ? 1.0 : n < 3.0 ? 2.0 : n < 7.0 ? 5.0 : 10.0) * mag;
    Axis a;
    a.lo = std::floor(lo / step + 1e-9) * step;
    a.hi = std::ceil(hi / step - 1e-9) * step;
    for (double t = a.lo; t <= a.hi + step * 1e-6; t += step)
        a.ticks.push_back(t);
    return a;
}

// Log axis over whole decades; with at most two decades the 2× and 5× ticks are labeled too.
Axis log_axis(double lo, double hi) {
    Axis a;
    a.log = true;
    a.lo = std::floor(std::log10(lo));
    a.hi = std::max(std::ceil(std::log10(hi)), a.lo + 1.0);
    const bool minor = a.hi - a.lo <= 2.0;
    for (double d = a.lo; d <= a.hi; d += 1.0) {
        a.ticks.push_back(d);
        if (minor && d < a.hi)
            for (double m : {2.0, 5.0})
                a.ticks.push_back(d + std::log10(m));
    }
    return a;
}

} // namespace

Image plot_lines(const std::vector<PlotSeries>& series, const PlotOptions& options) {
    const int left = 78, right = 24, top = 40, bottom = 56; // margins for labels
    if (options.width < left + right + 100 || options.height < top + bottom + 60)
        throw Error("plot: the image (" + std::to_string(options.width) + "x" +
                    std::to_string(options.height) + ") is too small");
    auto drawable = [&](double x, double y) {
        return std::isfinite(x) && std::isfinite(y) && (!options.log_y || y > 0);
    };
    double xlo = INFINITY, xhi = -INFINITY, ylo = INFINITY, yhi = -INFINITY;
    for (const PlotSeries& s : series) {
        if (s.x.size() != s.y.size())
            throw Error("plot: series '" + s.name + "' has x and y of different lengths");
        for (size_t i = 0; i < s.x.size(); ++i)
            if (drawable(s.x[i], s.y[i])) {
                xlo = std::min(xlo, s.x[i]), xhi = std::max(xhi, s.x[i]);
                ylo = std::min(ylo, s.y[i]), yhi = std::max(yhi, s.y[i]);
            }
    }
    if (!(xlo <= xhi))
        throw Error("plot: no series has a point to draw" +
                    std::string(options.log_y ? " (log y needs y > 0)" : ""));
    const Axis ax = linear_axis(xlo, xhi);
    const Axis ay = options.log_y ? log_axis(ylo, yhi) : linear_axis(ylo, yhi);

    Image image(options.width, options.height, Color3f(1.f));
    Canvas canvas(image);
    const Color3f black(0.f), grid = srgb(225, 225, 225), gray = srgb(90, 90, 90);
    const int px0 = left, px1 = options.width - right, py0 = top, py1 = options.height - bottom;
    auto to_x = [&](double x) { return px0 + (x - ax.lo) / (ax.hi - ax.lo) * (px1 - px0); };
    auto to_y = [&](double y) {
        const double v = options.log_y ? std::log10(y) : y;
        return py1 - (v - ay.lo) / (ay.hi - ay.lo) * (py1 - py0);
    };

    // Grid, ticks and tick labels.
    for (double t : ax.ticks) {
        const int x = int(std::lround(to_x(t)));
        canvas.fill_rect(x, py0, x + 1, py1, grid);
        canvas.fill_rect(x, py1, x + 1, py1 + 5, black);
        const std::string label = format_tick(t);
        canvas.text(x - text_width(label, 1) / 2, py1 + 9, label, 1, gray);
    }
    for (double t : ay.ticks) {
        const int y = int(std::lround(py1 - (t - ay.lo) / (ay.hi - ay.lo) * (py1 - py0)));
        canvas.fill_rect(px0, y, px1, y + 1, grid);
        canvas.fill_rect(px0 - 5, y, px0, y + 1, black);
        const std::string label = format_tick(ay.log ? std::pow(10.0, t) : t);
        canvas.text(px0 - 8 - text_width(label, 1), y - GlyphHeight / 2, label, 1, gray);
    }
    // Frame.
    canvas.fill_rect(px0, py0, px1 + 1, py0 + 1, black);
    canvas.fill_rect(px0, py1, px1 + 1, py1 + 1, black);
    canvas.fill_rect(px0, py0, px0 + 1, py1 + 1, black);
    canvas.fill_rect(px1, py0, px1 + 1, py1 + 1, black);

    // Curves.
    for (size_t k = 0; k < series.size(); ++k) {
        const PlotSeries& s = series[k];
        bool has_previous = false;
        double prev_x = 0, prev_y = 0;
        for (size_t i = 0; i < s.x.size(); ++i) {
            if (!drawable(s.x[i], s.y[i])) {
                has_previous = false;
                continue;
            }
            const double x = to_x(s.x[i]), y = to_y(s.y[i]);
            if (has_previous)
                canvas.line(prev_x, prev_y, x, y, 1.6f, palette(k));
            else
                canvas.line(x, y, x, y, 1.6f, palette(k));
            prev_x = x, prev_y = y, has_previous = true;
        }
    }

    // Title and axis labels (scale 2).
    if (!options.title.empty())
        canvas.text((px0 + px1 - text_width(options.title, 2)) / 2, (top - 2 * GlyphHeight) / 2,
                    options.title, 2, black);
    if (!options.x_label.empty())
        canvas.text((px0 + px1 - text_width(options.x_label, 2)) / 2, options.height - 2 * GlyphHeight - 8,
                    options.x_label, 2, black);
    if (!options.y_label.empty())
        canvas.text(8, (py0 + py1 + text_width(options.y_label, 2)) / 2, options.y_label, 2, black, true);

    // Legend, top right inside the frame.
    int legend_width = 0;
    for (const PlotSeries& s : series)
        legend_width = std::max(legend_width, text_width(s.name, 1));
    if (!series.empty()) {
        const int row = 14, lx1 = px1 - 8, lx0 = lx1 - legend_width - 40, ly0 = py0 + 8;
        const int ly1 = ly0 + int(series.size()) * row + 6;
        canvas.fill_rect(lx0, ly0, lx1, ly1, Color3f(1.f));
        canvas.fill_rect(lx0, ly0, lx1, ly0 + 1, gray);
        canvas.fill_rect(lx0, ly1 - 1, lx1, ly1, gray);
        canvas.fill_rect(lx0, ly0, lx0 + 1, ly1, gray);
        canvas.fill_rect(lx1 - 1, ly0, lx1, ly1, gray);
        for (size_t k = 0; k < series.size(); ++k) {
            const int y = ly0 + 4 + int(k) * row + row / 2;
            canvas.line(lx0 + 6, y, lx0 + 28, y, 2.f, palette(k));
            canvas.text(lx0 + 34, y - GlyphHeight / 2 - 1, series[k].name, 1, black);
        }
    }
    return image;
}

void write_plot(const std::string& path, const std::vector<PlotSeries>& series, const PlotOptions& options) {
    write_image(path, plot_lines(series, options));
}

} // namespace penumbra
