#include "diff/was/control_variate.h"

#include <cmath>

namespace penumbra {

// Inside the film P_j is the filter over its film mass (Film::filter_weight): differences of the uncut filter
// do not see the cut.
Vec2f filter_gradient_ratio(const Film& film, int px, int py, const Vec2f& offset, float pdf) {
    const Vec2f x(px + 0.5f + offset.x, py + 0.5f + offset.y);
    if (!film.sample_border &&
        (x.x < 0.f || x.y < 0.f || x.x > float(film.width) || x.y > float(film.height)))
        return Vec2f(0.f);
    constexpr float h = 1e-3f;
    const float mass = film.sample_border ? 1.f : film.film_mass(px, py);
    const auto P = [&](float dx, float dy) {
        return film.rfilter->eval_normalized(Vec2f(offset.x + dx, offset.y + dy));
    };
    return Vec2f(P(h, 0.f) - P(-h, 0.f), P(0.f, h) - P(0.f, -h)) * (0.5f / (h * pdf * mass));
}

std::vector<FilmCut> film_cuts(const Film& film, int px, int py) {
    std::vector<FilmCut> cuts;
    if (film.sample_border) return cuts;
    const float r = film.rfilter->radius(), mass = film.film_mass(px, py);
    const Vec2f c(px + 0.5f, py + 0.5f), size(float(film.width), float(film.height));
    for (int axis = 0; axis < 2; ++axis)
        for (int side = 0; side < 2; ++side) {
            const float center = axis == 0 ? c.x : c.y,
                        line = side == 0 ? 0.f : (axis == 0 ? size.x : size.y);
            if (std::abs(line - center) >= r) continue;
            const float other = axis == 0 ? c.y : c.x, extent = axis == 0 ? size.y : size.x;
            const float lo = std::max(other - r, 0.f), hi = std::min(other + r, extent);
            FilmCut cut;
            cut.normal = axis == 0 ? Vec2f(side == 0 ? -1.f : 1.f, 0.f) : Vec2f(0.f, side == 0 ? -1.f : 1.f);
            constexpr int N = 64;
            const float step = (hi - lo) / N;
            for (int i = 0; i < N; ++i) {
                const float t = lo + (i + 0.5f) * step - other;
                const Vec2f x = axis == 0 ? Vec2f(line - center, t) : Vec2f(t, line - center);
                const float P = film.rfilter->eval_normalized(x) / mass * step;
                cut.m0 += P;
                cut.m1 = cut.m1 + x * P;
            }
            cuts.push_back(cut);
        }
    return cuts;
}

// Integration by parts over the support ∩ the film (P_j vanishes on the rest of the support's edge and
// integrates to 1 over the film): E[C] = −tr(A) + Σ_cuts n·b ∫ P_j dℓ + n·A ∫ P_j x dℓ.
float control_correction(const LinearControlVariate& cv, const std::vector<FilmCut>& cuts, const Vec2f& x,
                         const Vec2f& score) {
    const Vec2f b = cv.mu_v * cv.mu_g;
    const Vec2f ax(LinearControlVariate::dot2(cv.row(0), x), LinearControlVariate::dot2(cv.row(1), x));
    const float C = LinearControlVariate::dot2(score, b + ax);
    float mean = cv.mean();
    for (const FilmCut& cut : cuts) {
        const Vec2f a1(LinearControlVariate::dot2(cv.row(0), cut.m1),
                       LinearControlVariate::dot2(cv.row(1), cut.m1));
        mean +=
            LinearControlVariate::dot2(cut.normal, b) * cut.m0 + LinearControlVariate::dot2(cut.normal, a1);
    }
    return -(C - mean);
}

} // namespace penumbra
