// A small line-plot writer for convergence curves: several named series on one chart, linear or log-scale y,
// axis ticks and labels (drawn with stb_easy_font) and a legend. Rendered into an Image; PNG via write_image.
#pragma once
#include "core/image.h"

#include <string>
#include <vector>

namespace penumbra {

struct PlotSeries {
    std::string name;         // legend entry
    std::vector<double> x, y; // same length; non-finite points (and y ≤ 0 on a log axis) break the line
};

struct PlotOptions {
    std::string title, x_label, y_label;
    bool log_y = false;
    int width = 720, height = 440;
};

// Draws the chart; series are colored from a fixed palette in order. Throws Error when no series has a point
// that can be drawn, or when the image is too small for the axes.
Image plot_lines(const std::vector<PlotSeries>& series, const PlotOptions& options);
// plot_lines written to `path` (.png, sRGB 8-bit; or .exr).
void write_plot(const std::string& path, const std::vector<PlotSeries>& series, const PlotOptions& options);

} // namespace penumbra
