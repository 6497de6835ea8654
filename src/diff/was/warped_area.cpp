#include "diff/was/warped_area.h"

#include "diff/auxiliary_rng.h"
#include "diff/film_sample.h"
#include "diff/material_form.h"
#include "diff/pixel_driver.h"
#include "diff/specular_chains.h"
#include "diff/was/auxiliary_rays.h"
#include "diff/was/control_variate.h"
#include "render/light_medium.h"
#include "render/path_tracer.h"

#include <cstdio>
#include <string>

namespace penumbra {

namespace {

// What the estimator of one scene shares across samples.
struct WasContext {
    const Scene& scene;
    const Parameters& params;
    MaterialForm form;
    BoundaryTest boundary;
    WarpOptions warp;
    PathSettings settings;
    float sigma;      // the film auxiliary distribution's standard deviation (pixels): the filter's
    Vec3f camera;     // the center of projection
    bool filter_jumps; // the filter jumps at its support's edge (box): a static discontinuity per pixel
    float film_scale;  // the boundary test's distance scale on the film: (pixels per radian)² / σ²

    WasContext(const Scene& s, const Parameters& p, const WasOptions& o)
        : scene(s), params(p), form(s, p, FirstVertex::Material), boundary(s), warp(o.warp), settings(o.path),
          sigma(filter_sigma(*s.sensor->film->rfilter)), camera(s.sensor->to_world.apply_point(Vec3f(0.f))),
          filter_jumps(penumbra::filter_jumps(*s.sensor->film->rfilter)) {
        // Pixels per radian at the film's center.
        const Film& film = *s.sensor->film;
        const Vec2f center(0.5f * float(film.width), 0.5f * float(film.height));
        const Vec3f d0 = s.sensor->sample_ray(center, Vec2f(0.5f)).first.d;
        const Vec3f d1 = s.sensor->sample_ray(center + Vec2f(1.f, 0.f), Vec2f(0.5f)).first.d;
        const float radians = 2.f * std::asin(std::min(1.f, 0.5f * norm(d1 - d0)));
        film_scale = 1.f / (radians * radians * sigma * sigma);
    }

    // The standard deviation of the normalized 1D filter profile (its second moment, by quadrature).
    static float filter_sigma(const ReconstructionFilter& f) {
        constexpr int N = 4096;
        const double r = f.radius(), h = 2.0 * r / N;
        double m0 = 0, m2 = 0;
        for (int i = 0; i < N; ++i) {
            const double x = -r + (i + 0.5) * h, v = f.eval(float(x));
            m0 += v;
            m2 += v * x * x;
        }
        return float(std::sqrt(m2 / m0));
    }
};

// The warp of direction ω at the surface vertex `hit` (x(θ) = si.p): Algorithm 2 or 3 with vMF auxiliary
// rays.
WarpEstimate warp_at(const WasContext& c, const SurfaceInteraction3f& hit, const SurfaceInteraction<Var>& si,
                     const Vec3f& omega, AuxiliaryRng& rng, RayCounter& rays) {
    const WarpEstimate e =
        estimate_warp_at(c.scene, c.form, c.boundary, WarpVertex{hit, si.p}, omega, c.warp, rng);
    rays.rays += uint64_t(c.warp.unbiased ? c.warp.rr_batch : c.warp.aux_count);
    return e;
}

// The vertex rule of warped-area sampling (render/path_tracer.h; Algorithm 1 lines 3–7): every non-delta
// direction ω sampled at x is warped, ω(θ) = ω + (θ − θ0) V(ω), with the Jacobian 1 + (θ − θ0) ∇·V, and the
// next vertex is where the warped ray meets the moving surface.
struct WasRule {
    const WasContext& c;
    AuxiliaryRng& rng;
    Vec3<Var> direction;          // the warped direction that reached the current vertex
    SurfaceInteraction<Var> next; // the vertex the last step placed

    SurfaceInteraction<Var> arrive(const SurfaceInteraction3f&, const SurfaceInteraction<Var>&) const {
        return next;
    }

    Color3<Var> emitted(const Emitter& e, const Color3f&, const SurfaceInteraction3f& hit,
                        const SurfaceInteraction<Var>& si, const Vec3f& d) const {
        return hit.is_valid() ? e.eval(si) : c.form.environment(c.scene, d, direction);
    }

    // Next-event estimation at x in solid angle: f_s(ω(θ)) L_e(y(θ) → x) J / p_σ, with y(θ) where the warped
    // ray meets the moving emitter (area lights) or the environment along ω(θ). Delta lights are connected in
    // material form (the light's position and x as they move; their shadows' motion is not seen, header).
    Color3<Var> next_event(const BSDF& bsdf, const SurfaceInteraction3f& hit, const SurfaceInteraction<Var>& si,
                           const DirectionSample3f& ds, const Color3f&, RayCounter& rays) {
        const BSDFContext ctx{TransportMode::Radiance};
        if (ds.emitter->is_delta()) return next_event_contribution(ctx, &bsdf, si, ds, c.form);
        const WarpEstimate e = warp_at(c, hit, si, ds.d, rng, rays);
        const Color3<Var> f = bsdf.eval(ctx, si, si.to_local(e.direction)) * (e.jacobian / Var(ds.pdf));
        if (const Shape* shape = ds.emitter->shape()) {
            const SurfaceInteraction3f light =
                surface_interaction<float>(*shape, ds.prim, ds.bary, MeshVertices{shape->mesh});
            SurfaceInteraction<Var> y = warped_vertex(c.params, light, si.p, e.direction);
            y.wi = y.to_local(-e.direction);
            return f * ds.emitter->eval(y);
        }
        return f * ds.emitter->eval_environment(c.form.direction_to_reference_light(*ds.emitter, ds.d) +
                                                (e.direction - Vec3<Var>(ds.d)));
    }

    void scatter(const BSDF& bsdf, const SurfaceInteraction3f& hit, const SurfaceInteraction<Var>& si,
                 const BSDFSample& bs, const Color3f& /*weight*/, const Vec3f& d,
                 const SurfaceInteraction3f& to, bool delta, Color3<Var>& throughput, RayCounter& rays) {
        const BSDFContext ctx{TransportMode::Radiance};
        if (delta) {
            // No integral over directions at a delta lobe: its direction turns with the geometry.
            direction = delta_step(bsdf, hit, si, bs, throughput);
        } else {
            const WarpEstimate e = warp_at(c, hit, si, d, rng, rays);
            direction = e.direction;
            throughput *= bsdf.eval(ctx, si, si.to_local(direction)) * (e.jacobian / Var(bs.pdf));
        }
        if (to.is_valid()) {
            next = warped_vertex(c.params, to, si.p, direction);
            next.wi = next.to_local(-direction);
        }
    }
};

// The film auxiliary sample at position `x` (Algorithm 2 on the film, §3.3): the boundary test of the point
// seen through x and its film motion ∂θ s(y(θ)) (the direct warp). Positions beyond the film's edge see the
// scene as well: the edge is not a boundary of the field (where the filters end, the film-edge term takes the
// flux across it: pixel_edge_velocity below).
void film_auxiliary(const WasContext& c, const Vec2f& x, const Vec2f& aperture, PixelAuxiliarySample& a,
                    RayCounter& rays) {
    const Sensor& sensor = *c.scene.sensor;
    a.warp = Vec2<Var>(x);
    const Ray ray = sensor.sample_ray(x, aperture).first;
    ++rays.rays;
    const SurfaceInteraction3f hit = c.scene.intersect(ray);
    a.boundary = c.boundary(hit, ray.o, ray.d, c.film_scale);
    // An escaped ray sees a direction: a far point moves on the film only with the camera's rotation.
    const Vec3<Var> y = hit.is_valid() ? auxiliary_point(c.form, c.boundary, hit, ray.o, ray.d)
                                       : Vec3<Var>(ray.o + ray.d * 1e4f);
    const Vec3<Var> p = c.form.to_reference_camera(y, c.camera);
    if (p.x.is_constant() && p.y.is_constant() && p.z.is_constant()) return;
    Vec2<Var> s;
    Var jacobian;
    if (!sensor.film_position(p, Vec3<Var>(ray.d * -1.f), s, jacobian)) return;
    a.warp = Vec2<Var>(Var(x.x, s.x.id), Var(x.y, s.y.id));
}

// ∂ω/∂x of the camera ray's direction at film position x (central differences; the direction is smooth).
std::pair<Vec3f, Vec3f> direction_gradient(const Sensor& sensor, const Vec2f& x, const Vec2f& aperture) {
    constexpr float h = 1e-2f;
    const auto d = [&](float dx, float dy) {
        return sensor.sample_ray(Vec2f(x.x + dx, x.y + dy), aperture).first.d;
    };
    return {(d(h, 0.f) - d(-h, 0.f)) * (0.5f / h), (d(0.f, h) - d(0.f, -h)) * (0.5f / h)};
}

// V(s) · across at a point s of a pixel edge or of the film's edge (the warp field of the film estimated there
// as at a camera sample), for the term −∮ P_j L (V · n_out) over the edges where the filters jump (the
// divergence theorem on the film with a field that does not vanish there; diff/pixel_boundary.h). The
// auxiliary stream is the edge sample's own, shared along a row or column like its path's.
Var pixel_edge_velocity(const WasContext& c, uint64_t seed, const Vec2f& s, const Vec2f& across, uint64_t stream,
                        RayCounter& rays) {
    AuxiliaryRng rng(seed ^ 0x5851F42D4C957F2DULL, stream, 0);
    const Vec2f aperture(0.5f);
    std::vector<PixelAuxiliarySample> aux = sample_pixel_auxiliary(c.sigma, c.warp, rng);
    for (PixelAuxiliarySample& a : aux)
        film_auxiliary(c, s + a.offset, aperture, a, rays);
    const PixelWarpEstimate e = estimate_pixel_warp(s, aux, c.sigma, c.warp);
    return (e.position.x - Var(s.x)) * Var(across.x) + (e.position.y - Var(s.y)) * Var(across.y);
}

// The film-edge term of a batch seed: V(s) in place of the material velocity.
PixelBoundary pixel_edge_term(const WasContext& c, uint64_t seed, int spp) {
    return PixelBoundary(
        c.scene,
        [&c, seed](const Vec2f& s, const Vec2f& across, uint64_t stream, RayCounter& rays) {
            return pixel_edge_velocity(c, seed, s, across, stream, rays);
        },
        film_edge_strata(*c.scene.sensor->film, spp));
}

// One camera sample of pixel (px, py): the film position x (diff/film_sample.h), warped on the film (value x,
// derivative V(x)), the camera ray through the warped position, P_j(x(θ)) J / p(x) and the path behind it.
struct CameraSample {
    Color3<Var> value;
    Color3f radiance;   // L(x): the value without P_j / p
    Vec2f offset;       // x − the pixel center
    float pdf = 0.f;    // p(x)
    Vec2<Var> position; // x(θ)
    bool on_film = false; // P_j(x) > 0
};

CameraSample camera_sample(const WasContext& c, Sampler& sampler, AuxiliaryRng& rng, int px, int py,
                           RayCounter& rays) {
    const Sensor& sensor = *c.scene.sensor;
    const Film& film = *sensor.film;
    const FilmSample fs = sample_film(*film.rfilter, sampler, false);
    const Vec2f x = Vec2f(px + 0.5f, py + 0.5f) + fs.offset;
    CameraSample out{Color3<Var>(Var(0.f)), Color3f(0.f), fs.offset, fs.pdf, Vec2<Var>(x)};
    const float P0 = film.filter_weight(px, py, x);
    if (!(P0 > 0.f)) return out;
    out.on_film = true;
    const Vec2f aperture = sampler.next_2d();
    const auto [ray, ray_weight] = sensor.sample_ray(x, aperture);
    ++rays.rays;

    std::vector<PixelAuxiliarySample> aux = sample_pixel_auxiliary(c.sigma, c.warp, rng);
    for (PixelAuxiliarySample& a : aux)
        film_auxiliary(c, x + a.offset, aperture, a, rays);
    const PixelWarpEstimate e = estimate_pixel_warp(x, aux, c.sigma, c.warp);
    out.position = e.position;

    const Var weight = film.filter_weight(px, py, e.position) / Var(fs.pdf) * e.jacobian * Var(ray_weight.x);
    const auto [dx, dy] = direction_gradient(sensor, x, aperture);
    const Vec3<Var> moved = Vec3<Var>(ray.d) + Vec3<Var>(dx) * (e.position.x - Var(x.x)) +
                            Vec3<Var>(dy) * (e.position.y - Var(x.y));
    const Vec3<Var> direction = c.form.direction_from_reference_camera(moved);
    const SurfaceInteraction3f first = c.scene.intersect(ray);
    Color3<Var> L(Var(0.f));
    if (!first.is_valid()) {
        if (!c.settings.hide_emitters) L = c.form.environment(c.scene, ray.d, direction);
    } else {
        SurfaceInteraction<Var> x1 = warped_vertex(c.params, first, c.form.camera_position(ray.o), direction);
        x1.wi = x1.to_local(-direction);
        WasRule rule{c, rng, Vec3<Var>(ray.d), {}};
        L = trace_path<Var>(c.scene, sampler, ray, first, x1, rule, c.settings, rays);
    }
    out.radiance = Color3f(L.x.v, L.y.v, L.z.v);
    out.value = L * weight;
    return out;
}

// The linear model of Appendix D fitted to a pixel's previous samples: least squares of y ≈ μ_y + ∇y · x for
// the radiance g (per channel) and the warp V, x the offset from the pixel center.
class PixelLinearModel {
  public:
    void add(const Vec2f& x, const Color3f& g, const Vec2f& v) {
        const double row[3] = {1.0, x.x, x.y}, y[5] = {g.x, g.y, g.z, v.x, v.y};
        for (int i = 0; i < 3; ++i) {
            for (int j = 0; j < 3; ++j)
                xtx_[i][j] += row[i] * row[j];
            for (int k = 0; k < 5; ++k)
                xty_[i][k] += row[i] * y[k];
        }
        ++n_;
    }
    bool ready() const { return n_ >= 6; }
    // The control variate of channel `ch` fitted so far; false until enough samples.
    bool fit(int ch, LinearControlVariate& cv) const {
        if (!ready()) return false;
        double coef[3][5];
        if (!solve(coef)) return false;
        cv.mu_g = float(coef[0][ch]);
        cv.grad_g = Vec2f(float(coef[1][ch]), float(coef[2][ch]));
        cv.mu_v = Vec2f(float(coef[0][3]), float(coef[0][4]));
        cv.jac_v[0] = Vec2f(float(coef[1][3]), float(coef[2][3]));
        cv.jac_v[1] = Vec2f(float(coef[1][4]), float(coef[2][4]));
        return true;
    }

  private:
    // XᵀX β = Xᵀy by Gaussian elimination with partial pivoting (3 × 3, 5 right-hand sides).
    bool solve(double (&beta)[3][5]) const {
        double a[3][8];
        for (int i = 0; i < 3; ++i) {
            for (int j = 0; j < 3; ++j)
                a[i][j] = xtx_[i][j];
            for (int k = 0; k < 5; ++k)
                a[i][3 + k] = xty_[i][k];
        }
        for (int col = 0; col < 3; ++col) {
            int pivot = col;
            for (int r = col + 1; r < 3; ++r)
                if (std::abs(a[r][col]) > std::abs(a[pivot][col])) pivot = r;
            if (!(std::abs(a[pivot][col]) > 1e-9 * n_)) return false;
            std::swap(a[col], a[pivot]);
            for (int r = 0; r < 3; ++r) {
                if (r == col) continue;
                const double f = a[r][col] / a[col][col];
                for (int j = col; j < 8; ++j)
                    a[r][j] -= f * a[col][j];
            }
        }
        for (int i = 0; i < 3; ++i)
            for (int k = 0; k < 5; ++k)
                beta[i][k] = a[i][3 + k] / a[i][i];
        return true;
    }

    double xtx_[3][3] = {}, xty_[3][5] = {};
    int n_ = 0;
};

// Was's camera samples of one tile: camera_sample with its own auxiliary stream, and with `control` (forward
// mode) the control variate of each pixel sample: the linear model fitted to the pixel's previous samples, or
// until it has enough of them, the previous pixel's of the tile (samples independent of the current one
// either way, so the control's known mean holds given them; tiles do not depend on the thread count).
class WasTile final : public TileSamples {
  public:
    WasTile(const WasContext& c, bool control) : c_(c), control_(control) {}

    Color3<Var> sample(Sampler& sampler, const PixelSample& s, RayCounter& rays) override {
        AuxiliaryRng rng(s.seed, s.pixel, uint64_t(s.m));
        last_ = camera_sample(c_, sampler, rng, s.x, s.y, rays);
        return last_.value;
    }
    void begin_pixel(int x, int y) override {
        x_ = x, y_ = y;
        cuts_ = control_ ? film_cuts(*c_.scene.sensor->film, x, y) : std::vector<FilmCut>();
        model_ = PixelLinearModel();
    }
    void correct(const std::vector<float>& tangent, Vec3d& d) override {
        if (!control_) return;
        const Film& film = *c_.scene.sensor->film;
        const Vec2f v(tangent_of(last_.position.x, tangent), tangent_of(last_.position.y, tangent));
        const Vec2f ratio = filter_gradient_ratio(film, x_, y_, last_.offset, last_.pdf);
        LinearControlVariate cv;
        const PixelLinearModel& fitted = model_.ready() ? model_ : previous_;
        for (int ch = 0; ch < 3; ++ch)
            if (fitted.fit(ch, cv)) d[ch] += control_correction(cv, cuts_, last_.offset, ratio);
        if (last_.on_film && std::isfinite(v.x) && std::isfinite(v.y))
            model_.add(last_.offset, last_.radiance, v);
    }
    void end_pixel() override {
        if (model_.ready()) previous_ = model_;
    }

  private:
    const WasContext& c_;
    bool control_;
    CameraSample last_;
    int x_ = 0, y_ = 0;
    std::vector<FilmCut> cuts_;
    PixelLinearModel model_, previous_;
};

// "consistent warped-area sampling, N' = 32, kappa = 10000, antithetic, control variate".
std::string describe_was(const WasOptions& o) {
    char kappa[32];
    std::snprintf(kappa, sizeof(kappa), "%g", double(o.warp.weight.kappa));
    return std::string(o.warp.unbiased ? "unbiased" : "consistent") + " warped-area sampling, " +
           (o.warp.unbiased ? "N' ~ Geom" : "N' = " + std::to_string(o.warp.aux_count)) +
           ", kappa = " + kappa + (o.warp.antithetic ? ", antithetic" : "") +
           (o.control_variate ? ", control variate" : "");
}

// The loop of was: its tiles (with the control variate in forward mode unless disabled or the filter is a
// box, whose gradient term is all at its edges: the film-edge term) and the film-edge term.
PixelLoop was_loop(const Scene& scene, const Parameters& params, const WasOptions& options, bool forward) {
    require_was_support(scene, params);
    PixelLoop loop(scene, params, options);
    const auto c = std::make_shared<const WasContext>(scene, params, options);
    const bool control = forward && options.control_variate && !c->filter_jumps;
    loop.tiles = [c, control] { return std::make_unique<WasTile>(*c, control); };
    loop.film_edge = [c, spp = options.spp](uint64_t seed) { return pixel_edge_term(*c, seed, spp); };
    loop.unwarped_delta_lights = "was";
    loop.description = describe_was(options);
    loop.term = "warped-area";
    return loop;
}

} // namespace

void require_was_support(const Scene& scene, const Parameters& params) {
    require_film(scene, params);
    if (scene_has_media(scene))
        throw Error(
            "method was (paper 004) differentiates surfaces only and the scene has participating media: "
            "use the psdr method (the default)");
    if (!scene.sensor->projects_points())
        throw Error(
            "method was warps the film: it needs a sensor with one center of projection (perspective, "
            "orthographic, thinlens with aperture 0)");
    require_no_moving_edges_behind_delta_lobes(scene, params, "was");
}

DerivativeImage was_derivative(const Scene& scene, const Parameters& params, const WasOptions& options) {
    return pixel_derivative(was_loop(scene, params, options, true));
}

Gradient was_gradient(const Scene& scene, const Parameters& params, const Image& adjoint,
                      const WasOptions& options) {
    return pixel_gradient(was_loop(scene, params, options, false), adjoint);
}

} // namespace penumbra
