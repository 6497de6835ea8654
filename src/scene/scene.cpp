#include "scene/scene.h"

#include <embree3/rtcore.h>

#include <cstring>
#include <map>
#include <set>
#include <string>

namespace penumbra {

// Top-level geometry ids: shapes first (id = index in `shapes`), then instances (id = shapes.size() + index).
struct Scene::EmbreeState {
    RTCDevice device = nullptr;
    RTCScene scene = nullptr;
    std::map<const ShapeGroup*, RTCScene> groups; // one BVH per instanced group, shared by its instances
    std::string error;
    ~EmbreeState() {
        for (auto& [group, bvh] : groups)
            rtcReleaseScene(bvh);
        if (scene) rtcReleaseScene(scene);
        if (device) rtcReleaseDevice(device);
    }
};

Scene::Scene() = default;
Scene::~Scene() = default;

size_t Scene::triangle_count() const {
    size_t n = 0;
    for (const auto& s : shapes) n += s->mesh.face_count();
    std::set<const ShapeGroup*> groups;
    for (const auto& i : instances)
        if (groups.insert(i->group.get()).second) n += i->group->triangle_count();
    return n;
}

size_t Scene::instanced_triangle_count() const {
    size_t n = 0;
    for (const auto& s : shapes)
        n += s->mesh.face_count();
    for (const auto& i : instances)
        n += i->group->triangle_count();
    return n;
}

namespace {

// A triangle geometry of `mesh` attached to `bvh` under `id`; returns the mesh bounds via lo, hi.
void attach_mesh(RTCDevice device, RTCScene bvh, const TriangleMesh& mesh, unsigned id, Vec3f& lo,
                 Vec3f& hi) {
    RTCGeometry geom = rtcNewGeometry(device, RTC_GEOMETRY_TYPE_TRIANGLE);
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
    auto* idx = static_cast<uint32_t*>(rtcSetNewGeometryBuffer(
        geom, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3, sizeof(uint32_t) * 3, mesh.face_count()));
    std::memcpy(idx, mesh.indices.data(), mesh.indices.size() * sizeof(uint32_t));
    rtcCommitGeometry(geom);
    rtcAttachGeometryByID(bvh, geom, id);
    rtcReleaseGeometry(geom);
}

// Embree's 3x4 column-major affine matrix of a transform.
void to_embree(const Transform& t, float xfm[12]) {
    for (int col = 0; col < 4; ++col)
        for (int row = 0; row < 3; ++row)
            xfm[3 * col + row] = t.matrix.m[row][col];
}

} // namespace

void Scene::select_sensor(const std::string& which) {
    std::string names;
    for (size_t i = 0; i < sensors.size(); ++i) {
        if (which == std::to_string(i) || (!sensors[i]->id.empty() && which == sensors[i]->id)) {
            sensor = sensors[i];
            return;
        }
        names +=
            (i ? ", " : "") + std::to_string(i) + (sensors[i]->id.empty() ? "" : " (" + sensors[i]->id + ")");
    }
    throw Error("unknown sensor '" + which + "' (the scene's sensors: " + names + ")");
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
    if (robust_intersections) rtcSetSceneFlags(embree_->scene, RTC_SCENE_FLAG_ROBUST);

    Vec3f lo(Infinity), hi(-Infinity);
    for (unsigned id = 0; id < shapes.size(); ++id)
        attach_mesh(embree_->device, embree_->scene, shapes[id]->mesh, id, lo, hi);
    std::map<const ShapeGroup*, std::pair<Vec3f, Vec3f>> group_bounds;
    for (unsigned i = 0; i < instances.size(); ++i) {
        const Instance& instance = *instances[i];
        const ShapeGroup* group = instance.group.get();
        if (!embree_->groups.count(group)) {
            RTCScene bvh = rtcNewScene(embree_->device);
            rtcSetSceneBuildQuality(bvh, RTC_BUILD_QUALITY_HIGH);
            if (robust_intersections) rtcSetSceneFlags(bvh, RTC_SCENE_FLAG_ROBUST);
            Vec3f glo(Infinity), ghi(-Infinity);
            for (unsigned id = 0; id < group->shapes.size(); ++id)
                attach_mesh(embree_->device, bvh, group->shapes[id]->mesh, id, glo, ghi);
            rtcCommitScene(bvh);
            embree_->groups[group] = bvh;
            group_bounds[group] = {glo, ghi};
        }
        RTCGeometry geom = rtcNewGeometry(embree_->device, RTC_GEOMETRY_TYPE_INSTANCE);
        rtcSetGeometryInstancedScene(geom, embree_->groups[group]);
        float xfm[12];
        to_embree(instance.to_world, xfm);
        rtcSetGeometryTransform(geom, 0, RTC_FORMAT_FLOAT3X4_COLUMN_MAJOR, xfm);
        rtcCommitGeometry(geom);
        rtcAttachGeometryByID(embree_->scene, geom, unsigned(shapes.size()) + i);
        rtcReleaseGeometry(geom);
        const auto [glo, ghi] = group_bounds[group];
        for (int corner = 0; corner < 8; ++corner) {
            const Vec3f p = instance.to_world.apply_point(
                Vec3f(corner & 1 ? ghi.x : glo.x, corner & 2 ? ghi.y : glo.y, corner & 4 ? ghi.z : glo.z));
            lo = min(lo, p);
            hi = max(hi, p);
        }
    }
    rtcCommitScene(embree_->scene);
    if (!embree_->error.empty()) throw Error("Embree: " + embree_->error);

    if (shapes.empty() && instances.empty()) {
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

void Scene::flatten_instances() {
    if (instances.empty()) return;
    for (const auto& instance : instances) {
        const auto& group = instance->group->shapes;
        for (size_t k = 0; k < group.size(); ++k) {
            auto copy = std::make_shared<Shape>(*group[k]);
            copy->group_shape = group[k].get();
            copy->instance_to_world = instance->to_world;
            copy->vertex_param_index = -1;
            copy->update_from_group();
            copy->finalize();
            if (!instance->id.empty()) {
                copy->id = group.size() == 1 ? instance->id
                                             : instance->id + "." +
                                                   (group[k]->id.empty() ? std::to_string(k) : group[k]->id);
                instance_shapes[instance->id].push_back(copy.get());
            }
            shapes.push_back(std::move(copy));
        }
    }
    instances.clear();
    build();
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
    if (rh.hit.instID[0] != RTC_INVALID_GEOMETRY_ID) {
        const Instance& instance = *instances[rh.hit.instID[0] - shapes.size()];
        return instance.compute_surface_interaction(ray, rh.ray.tfar, *instance.group->shapes[rh.hit.geomID],
                                                    rh.hit.primID, rh.hit.u, rh.hit.v);
    }
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
