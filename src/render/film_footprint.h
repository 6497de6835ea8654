// The pixels a film sample reaches through the reconstruction filter (splatting: light tracing, boundary terms).
#pragma once
#include "scene/film.h"

#include <algorithm>
#include <cmath>

namespace penumbra {

// visit(x, y, P_j(s)) for every pixel j whose normalized filter P_j (Film::filter_weight) is nonzero at film
// position s (pixels).
template <typename Visit> void for_each_pixel_in_footprint(const Film& film, const Vec2f& s, const Visit& visit) {
    const float r = film.rfilter->radius();
    const int x0 = std::max(0, int(std::floor(s.x - r - 0.5f))), x1 = std::min(film.width - 1, int(s.x + r));
    const int y0 = std::max(0, int(std::floor(s.y - r - 0.5f))), y1 = std::min(film.height - 1, int(s.y + r));
    for (int y = y0; y <= y1; ++y)
        for (int x = x0; x <= x1; ++x) {
            const float w = film.filter_weight(x, y, s);
            if (w != 0.f) visit(x, y, w);
        }
}

} // namespace penumbra
