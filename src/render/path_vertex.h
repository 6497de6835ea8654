// Path-space vertices for bidirectional estimators (Veach 1997, ch. 10): a path x̄ = x_0 ... x_k is built from
// a light subpath y_0 ... y_{s-1} and a camera subpath z_{t-1} ... z_0, and each vertex carries the densities
// of being sampled from either side. Densities are per unit area for surface vertices and per unit volume for
// medium vertices (§10.2: p_A(x') = p_σ(x → x') |cos θ'| / d² on surfaces; in a medium the solid-angle
// density is multiplied by the free-flight density of stopping at x' and divided by d², and surface vertices
// reached through a medium also carry the probability of passing it). The MIS weight of strategy (s, t) is
// computed from the ratios p_{i}/p_{i±1} = pdf_rev / pdf_fwd of these densities (Eqs. 10.9-10.10).
#pragma once
#include "scene/emitter.h"
#include "scene/medium.h"

namespace penumbra {

enum class VertexType { Camera, Light, Surface, Medium };

struct PathVertex {
    VertexType type = VertexType::Surface;
    Vec3f p;                        // position (a point on the sensor's lens / the emitter for endpoints)
    Vec3f n;                        // geometric normal; zero for medium vertices and point-like endpoints
    SurfaceInteraction3f si;        // the surface interaction (si.wi toward the previous subpath vertex)
    Vec3f wi;                       // world direction toward the previous subpath vertex (zero at endpoints)
    Vec3f d_env;                    // infinite vertices: the world direction from the scene toward the light
    const Medium* medium = nullptr; // medium the vertex lies in (surfaces: the medium of the arriving ray)
    const Emitter* emitter = nullptr; // light endpoints, and surfaces that emit
    Color3f beta{1.f, 1.f, 1.f};      // subpath throughput up to and including this vertex's sampling density
    float pdf_fwd = 0.f;              // density of this vertex when sampled by its own subpath
    float pdf_rev = 0.f;              // density of this vertex when sampled from the other side
    // Free-flight factors of the segment from the previous subpath vertex, in the walk's direction (part of
    // pdf_fwd) and in the reverse one (part of the previous vertex's pdf_rev); 1 in vacuum.
    float ff_fwd = 1.f, ff_rev = 1.f;
    bool delta = false;    // scattered by a delta BSDF lobe (no connection can use this vertex)
    float eta = 1.f;       // delta vertices: the relative index η_out / η_in along the sampled lobe (1: reflection)
    bool infinite = false; // an escaped camera ray (the environment) or an infinite light's endpoint

    // Densities toward this vertex carry the |cos| of its normal (surfaces and area-light endpoints).
    bool on_surface() const { return !infinite && squared_norm(n) > 0.f; }
};

} // namespace penumbra
