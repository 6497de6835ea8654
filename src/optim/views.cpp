#include "optim/views.h"

#include "core/error.h"
#include "core/rng.h"
#include "scene/scene.h"

#include <nlohmann/json.hpp>

#include <algorithm>
#include <filesystem>
#include <numeric>
#include <set>

namespace penumbra {

namespace {

using nlohmann::json;

std::string type_name(const json& j) { return j.is_number() ? "number" : j.type_name(); }

[[noreturn]] void fail(const std::string& source, const std::string& key, const std::string& expected,
                       const json& got) {
    throw Error(source + ": key '" + key + "': expected " + expected + ", got " + type_name(got));
}

void check_keys(const json& j, const std::set<std::string>& known, const std::string& where,
                const std::string& source) {
    for (auto it = j.begin(); it != j.end(); ++it)
        if (!known.count(it.key())) {
            std::string expected;
            for (const std::string& k : known)
                expected += (expected.empty() ? "" : ", ") + k;
            throw Error(source + ": unknown key '" + where + "." + it.key() + "' (expected: " + expected +
                        ")");
        }
}

Vec3f vec3(const json& j, const std::string& key, const std::string& source) {
    if (!j.is_array() || j.size() != 3 || !j[0].is_number() || !j[1].is_number() || !j[2].is_number())
        fail(source, key, "3 numbers [x, y, z]", j);
    return {j[0].get<float>(), j[1].get<float>(), j[2].get<float>()};
}

CameraPose parse_pose(const json& j, const std::string& where, const std::string& source) {
    if (!j.is_object()) fail(source, where, "an object {\"origin\", \"target\", \"up\"}", j);
    check_keys(j, {"origin", "target", "up"}, where, source);
    CameraPose pose;
    for (const char* key : {"origin", "target", "up"})
        if (!j.contains(key)) throw Error(source + ": missing key '" + where + "." + key + "'");
    pose.origin = vec3(j["origin"], where + ".origin", source);
    pose.target = vec3(j["target"], where + ".target", source);
    pose.up = vec3(j["up"], where + ".up", source);
    const Vec3f forward = pose.target - pose.origin;
    if (!(norm(forward) > 0.f) || !(norm(cross(forward, pose.up)) > 1e-6f * norm(forward) * norm(pose.up)))
        throw Error(source + ": key '" + where +
                    "': origin and target must differ and up must not be parallel "
                    "to the viewing direction");
    return pose;
}

} // namespace

std::vector<ViewSpec> parse_views(const json& j, const std::string& base_dir, const std::string& source) {
    if (!j.is_array() || j.empty()) fail(source, "views", "a non-empty array of views", j);
    std::vector<ViewSpec> views;
    for (size_t i = 0; i < j.size(); ++i) {
        const std::string where = "views[" + std::to_string(i) + "]";
        const json& v = j[i];
        if (!v.is_object()) fail(source, where, "an object", v);
        check_keys(v, {"image", "look_at", "name", "sensor"}, where, source);
        ViewSpec view;
        if (v.contains("sensor")) {
            const json& s = v["sensor"];
            if (s.is_string())
                view.sensor = s.get<std::string>();
            else if (s.is_number_integer() && s.get<int64_t>() >= 0)
                view.sensor = std::to_string(s.get<int64_t>());
            else
                fail(source, where + ".sensor", "a sensor id (string) or index (non-negative integer)", s);
        }
        if (v.contains("look_at")) view.pose = parse_pose(v["look_at"], where + ".look_at", source);
        if (view.sensor.empty() && !view.pose)
            throw Error(source + ": " + where + " needs a 'sensor', a 'look_at' camera pose, or both");
        if (v.contains("image")) {
            if (!v["image"].is_string()) fail(source, where + ".image", "a path", v["image"]);
            const std::filesystem::path path = v["image"].get<std::string>();
            view.target_image = path.is_absolute()
                                    ? path.string()
                                    : (std::filesystem::path(base_dir) / path).lexically_normal().string();
        }
        if (v.contains("name")) {
            if (!v["name"].is_string() || v["name"].get<std::string>().empty())
                fail(source, where + ".name", "a non-empty string", v["name"]);
            view.name = v["name"].get<std::string>();
        }
        views.push_back(std::move(view));
    }
    return views;
}

ViewSelector::ViewSelector(Scene& scene, std::vector<ViewSpec> views)
    : scene_(scene), views_(std::move(views)), saved_selection_(scene.sensor) {
    for (const std::shared_ptr<Sensor>& s : scene.sensors)
        saved_to_world_.push_back(std::make_unique<Transform>(s->to_world));
    std::set<std::string> names;
    for (size_t i = 0; i < views_.size(); ++i) {
        ViewSpec& v = views_[i];
        if (v.sensor.empty()) {
            sensors_.push_back(scene.sensor);
        } else {
            try {
                scene.select_sensor(v.sensor);
            } catch (const Error& e) {
                scene.sensor = saved_selection_;
                throw Error("view " + std::to_string(i) + (v.name.empty() ? "" : " ('" + v.name + "')") +
                            ": " + e.what());
            }
            sensors_.push_back(scene.sensor);
        }
        if (v.pose && !sensors_.back()->projects_points())
            throw Error("view " + std::to_string(i) + ": a look_at pose needs a projective camera");
        if (v.name.empty())
            v.name = v.pose                         ? "pose" + std::to_string(i)
                     : !sensors_.back()->id.empty() ? sensors_.back()->id
                                                    : "view" + std::to_string(i);
        if (!names.insert(v.name).second) throw Error("two views are named '" + v.name + "'");
    }
    scene.sensor = saved_selection_;
}

ViewSelector::~ViewSelector() {
    for (size_t i = 0; i < scene_.sensors.size() && i < saved_to_world_.size(); ++i)
        if (!(scene_.sensors[i]->to_world.matrix == saved_to_world_[i]->matrix))
            scene_.sensors[i]->set_transform(*saved_to_world_[i]);
    scene_.sensor = saved_selection_;
}

void ViewSelector::select(size_t i) {
    const ViewSpec& v = views_.at(i);
    Sensor& sensor = *sensors_[i];
    // The sensor's own to_world unless the view places it; several views may share one sensor at other poses.
    const auto own = std::find(scene_.sensors.begin(), scene_.sensors.end(), sensors_[i]);
    const Transform to_world = v.pose ? Transform::look_at(v.pose->origin, v.pose->target, v.pose->up)
                               : own != scene_.sensors.end()
                                   ? *saved_to_world_[size_t(own - scene_.sensors.begin())]
                                   : sensor.to_world;
    if (!(sensor.to_world.matrix == to_world.matrix)) sensor.set_transform(to_world);
    scene_.sensor = sensors_[i];
}

int ViewSelector::width(size_t i) const { return sensors_.at(i)->film->width; }
int ViewSelector::height(size_t i) const { return sensors_.at(i)->film->height; }

std::vector<size_t> views_of_iteration(size_t count, int per_iteration, uint64_t seed, int iteration) {
    std::vector<size_t> all(count);
    std::iota(all.begin(), all.end(), size_t(0));
    if (per_iteration <= 0 || size_t(per_iteration) >= count) return all;
    PCG32 rng(mix_bits(seed ^ 0x5851f42d4c957f2dULL), uint64_t(iteration));
    for (size_t k = 0; k < size_t(per_iteration); ++k) {
        const size_t j = k + std::min(count - k - 1, size_t(rng.next_float() * float(count - k)));
        std::swap(all[k], all[j]);
    }
    all.resize(size_t(per_iteration));
    std::sort(all.begin(), all.end());
    return all;
}

} // namespace penumbra
