#include "scene/scene.h"

#include <embree3/rtcore.h>

#include <cstring>
#include <string>

namespace penumbra {

struct Scene::EmbreeState {
    RTCDevice device = nullptr;
    RTCScene scene = nullptr;
    std::string error;
    ~EmbreeState() {
        if (scene) rtcReleaseScene(scene);
        if (device) rtcReleaseDevice(device);
    }
};

Scene::Scene() = default;
Scene::~Scene() = default;

size_t Scene::triangle_count() const {
    size_t n = 0;
    for (const auto& s : shapes) n += s->mesh.face_count();
    return n;
}

void Scene::build() {
    if (!sensor) throw Error("scene has no sensor");
    embree_ = std::make_unique<EmbreeState>();
    embree_->device = rtcNewDevice(nullptr);
    if (!embree_->device) throw Error("Embree: could not create a device");
    rtcSetDeviceErrorFunction(
        embree_->device,
        [](void* user, RTCError, const char* msg) { static_cast<EmbreeState*>(user)->error = msg; },
        embree_.get());
    embree_->scene = rtcNewScene(embree_->device);
    rtcSetSceneBuildQuality(embree_->scene, RTC_BUILD_QUALITY_HIGH);
    rtcSetSceneFlags(embree_->scene, RTC_SCENE_FLAG_ROBUST);

    Vec3f lo(Infinity), hi(-Infinity);
    for (unsigned id = 0; id < shapes.size(); ++id) {
        const TriangleMesh& mesh = shapes[id]->mesh;
        RTCGeometry geom = rtcNewGeometry(embree_->device, RTC_GEOMETRY_TYPE_TRIANGLE);
        // Embree-allocated buffers carry the padding its SIMD loads need.
        auto* v = static_cast<float*>(rtcSetNewGeometryBuffer(geom, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3,
                                                              sizeof(float) * 3, mesh.vertex_count()));
        for (size_t i = 0; i < mesh.vertex_count(); ++i) {
            const Vec3f& p = mesh.positions[i];
            v[3 * i] = p.x;
            v[3 * i + 1] = p.y;
            v[3 * i + 2] = p.z;
            lo = min(lo, p);
            hi = max(hi, p);
        }
        auto* idx = static_cast<uint32_t*>(rtcSetNewGeometryBuffer(geom, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3,
                                                                   sizeof(uint32_t) * 3, mesh.face_count()));
        std::memcpy(idx, mesh.indices.data(), mesh.indices.size() * sizeof(uint32_t));
        rtcCommitGeometry(geom);
        rtcAttachGeometryByID(embree_->scene, geom, id);
        rtcReleaseGeometry(geom);
    }
    rtcCommitScene(embree_->scene);
    if (!embree_->error.empty()) throw Error("Embree: " + embree_->error);

    if (shapes.empty()) {
        bounds_ = {Vec3f(0.f), 1.f};
    } else {
        bounds_.center = (lo + hi) * 0.5f;
        bounds_.radius = std::max(norm(hi - lo) * 0.5f, 1e-3f);
    }
    infinite_emitters_.clear();
    for (const auto& e : emitters) {
        e->set_scene_bounds(bounds_);
        if (e->is_infinite()) infinite_emitters_.push_back(e.get());
    }
}

static void to_embree(const Ray& ray, RTCRay& r) {
    r.org_x = ray.o.x;
    r.org_y = ray.o.y;
    r.org_z = ray.o.z;
    r.dir_x = ray.d.x;
    r.dir_y = ray.d.y;
    r.dir_z = ray.d.z;
    r.tnear = 0.f;
    r.tfar = ray.tmax;
    r.time = 0.f;
    r.mask = 0xFFFFFFFFu;
    r.id = 0;
    r.flags = 0;
}

SurfaceInteraction3f Scene::intersect(const Ray& ray) const {
    RTCIntersectContext ctx;
    rtcInitIntersectContext(&ctx);
    RTCRayHit rh;
    to_embree(ray, rh.ray);
    rh.hit.geomID = RTC_INVALID_GEOMETRY_ID;
    rh.hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
    rtcIntersect1(embree_->scene, &ctx, &rh);
    if (rh.hit.geomID == RTC_INVALID_GEOMETRY_ID) return {};
    return shapes[rh.hit.geomID]->compute_surface_interaction(ray, rh.ray.tfar, rh.hit.primID, rh.hit.u, rh.hit.v);
}

bool Scene::occluded(const Ray& ray) const {
    RTCIntersectContext ctx;
    rtcInitIntersectContext(&ctx);
    RTCRay r;
    to_embree(ray, r);
    rtcOccluded1(embree_->scene, &ctx, &r);
    return r.tfar < 0.f;
}

std::pair<DirectionSample3f, Color3f> Scene::sample_emitter_direction(const Interaction3f& ref, const Vec2f& u,
                                                                     bool test_visibility) const {
    if (emitters.empty()) return {DirectionSample3f(), Color3f(0.f)};
    const size_t n = emitters.size();
    float ux = u.x * float(n);
    const size_t index = std::min(size_t(ux), n - 1);
    ux -= float(index);
    auto [ds, weight] = emitters[index]->sample_direction(ref, Vec2f(ux, u.y));
    ds.emitter = emitters[index].get();
    ds.pdf /= float(n);
    weight *= float(n);
    if (test_visibility && !is_black(weight)) {
        const Ray shadow = std::isinf(ds.dist) ? ref.spawn_ray(ds.d) : ref.spawn_ray_to(ds.p);
        if (occluded(shadow)) weight = Color3f(0.f);
    }
    return {ds, weight};
}

float Scene::pdf_emitter_direction(const Interaction3f& ref, const DirectionSample3f& ds) const {
    if (!ds.emitter || emitters.empty()) return 0.f;
    return ds.emitter->pdf_direction(ref, ds) / float(emitters.size());
}

size_t Scene::sample_emitter_index(float& u, float& pdf) const {
    const size_t n = emitters.size();
    const size_t index = std::min(size_t(u * float(n)), n - 1);
    u = u * float(n) - float(index);
    pdf = 1.f / float(n);
    return index;
}

const Emitter* Scene::sample_emitter(float& u, float& pdf) const {
    if (emitters.empty()) return nullptr;
    return emitters[sample_emitter_index(u, pdf)].get();
}

Color3f Scene::eval_environment(const Vec3f& d) const {
    Color3f L(0.f);
    for (const Emitter* e : infinite_emitters_) L += e->eval_environment(d);
    return L;
}

} // namespace penumbra
