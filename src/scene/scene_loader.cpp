// XmlScene -> Scene: instantiates declarations bottom-up through the per-kind factories, like Mitsuba 3's
// instantiate_node(): children first, each object once (a <ref> yields the same instance), then the parent's
// factory, then a check that every declared parameter was understood. The scene keeps top-level shapes (and
// their area emitters), emitters, the sensors (default: one perspective) and the integrator (default:
// path).
#include "scene/factory.h"
#include "scene/scene.h"
#include "scene/xml_parser.h"

#include <set>

namespace penumbra {
namespace {

using Factory = std::shared_ptr<Object> (*)(const Properties&, const LoadContext&);

Factory factory_for(ObjectKind kind) {
    switch (kind) {
    case ObjectKind::Shape:
        return make_shape;
    case ObjectKind::BSDF:
        return make_bsdf;
    case ObjectKind::Texture:
        return make_texture;
    case ObjectKind::Emitter:
        return make_emitter;
    case ObjectKind::Sensor:
        return make_sensor;
    case ObjectKind::Film:
        return make_film;
    case ObjectKind::RFilter:
        return make_rfilter;
    case ObjectKind::Sampler:
        return make_sampler;
    case ObjectKind::Integrator:
        return make_integrator_settings;
    case ObjectKind::Medium:
        return make_medium;
    case ObjectKind::Phase:
        return make_phase;
    case ObjectKind::Volume:
        return make_volume;
    }
    return nullptr;
}

template <typename T> std::shared_ptr<T> as(const std::shared_ptr<Object>& obj, ObjectKind kind) {
    auto typed = std::dynamic_pointer_cast<T>(obj);
    if (!typed)
        throw LoadError(obj->location, std::string("internal error: the ") + kind_name(kind) +
                                           " factory for '" + obj->plugin +
                                           "' returned an object of another kind");
    return typed;
}

class Instantiator {
  public:
    explicit Instantiator(const XmlScene& xml) { ctx_.search_paths = xml.search_paths; }

    std::shared_ptr<Object> instantiate(const XmlNode& node) {
        if (const auto it = done_.find(&node); it != done_.end()) return it->second;
        if (!active_.insert(&node).second)
            throw LoadError(node.location, "circular reference: " + std::string(kind_name(node.kind)) + " '" +
                                               node.id + "' (directly or indirectly) contains itself");
        Properties props = node.props;
        for (const XmlChild& child : node.children)
            props.add_object(child.name, instantiate(*child.node), child.location);
        std::shared_ptr<Object> obj = create(node.kind, props);
        props.check_all_queried(std::string(kind_name(node.kind)) + " '" + node.type + "'");
        obj->id = node.id;
        obj->plugin = node.type;
        obj->location = node.location;
        active_.erase(&node);
        done_[&node] = obj;
        return obj;
    }

    std::shared_ptr<Object> create(ObjectKind kind, const Properties& props) const {
        std::shared_ptr<Object> obj = factory_for(kind)(props, ctx_);
        if (!obj || obj->kind() != kind)
            throw LoadError(props.location(), std::string("internal error: the ") + kind_name(kind) +
                                                  " factory returned no " + kind_name(kind) + " for '" +
                                                  props.plugin() + "'");
        return obj;
    }

  private:
    LoadContext ctx_;
    std::map<const XmlNode*, std::shared_ptr<Object>> done_;
    std::set<const XmlNode*> active_;
};

// A shapegroup is a declaration for instances to reference; it is not rendered by itself (as in Mitsuba).
void add_shape(Scene& scene, const std::shared_ptr<Object>& obj) {
    if (std::dynamic_pointer_cast<ShapeGroup>(obj)) return;
    if (auto instance = std::dynamic_pointer_cast<Instance>(obj)) {
        scene.instances.push_back(std::move(instance));
        return;
    }
    auto shape = as<Shape>(obj, ObjectKind::Shape);
    scene.shapes.push_back(shape);
    if (shape->emitter) {
        shape->emitter->set_shape(shape.get());
        scene.emitters.push_back(shape->emitter);
    }
    if (shape->sensor) scene.sensors.push_back(shape->sensor);
}

std::unique_ptr<Scene> build_scene(const XmlScene& xml, const std::string& source_path) {
    auto scene = std::make_unique<Scene>();
    scene->source_path = source_path;
    // Mitsuba 3's one scene parameter (its default: Embree's faster, non-watertight triangle test).
    scene->robust_intersections = xml.props.get_bool("embree_use_robust_intersections", false);
    xml.props.check_all_queried("<scene>");
    Instantiator inst(xml);
    std::vector<std::pair<const Emitter*, SourceLocation>> top_level_area_emitters;
    for (const XmlChild& child : xml.objects) {
        const std::shared_ptr<Object> obj = inst.instantiate(*child.node);
        switch (obj->kind()) {
        case ObjectKind::Shape:
            add_shape(*scene, obj);
            break;
        case ObjectKind::Emitter: {
            auto emitter = as<Emitter>(obj, ObjectKind::Emitter);
            // A top-level area emitter is declared for a shape to <ref> (possibly further down): its shape adds
            // it to the scene; it is an error only if no shape uses it (checked below).
            if (emitter->flags() & EmitterSurface) top_level_area_emitters.emplace_back(emitter.get(), child.location);
            else scene->emitters.push_back(std::move(emitter));
            break;
        }
        case ObjectKind::Sensor:
            scene->sensors.push_back(as<Sensor>(obj, ObjectKind::Sensor));
            break;
        case ObjectKind::Integrator:
            if (scene->integrator)
                throw LoadError(child.location,
                                "only one <integrator> may be specified per scene (the first is at " +
                                    scene->integrator->location.str() + ")");
            scene->integrator = as<const IntegratorSettings>(obj, ObjectKind::Integrator);
            break;
        default:
            break; // BSDFs, textures, media, ... declared at the top level for later <ref>s (as in Mitsuba)
        }
    }
    for (const auto& [emitter, location] : top_level_area_emitters)
        if (!emitter->shape())
            throw LoadError(location, "an area emitter must be attached to a shape (nest it in the <shape>, or <ref> it from one)");
    // Every id and alias (all declarations are instantiated by now: each is top-level or nested in one).
    for (const auto& [id, node] : xml.ids)
        scene->named_objects[id] = inst.instantiate(*node);
    // Mitsuba's defaults: a perspective sensor with its default film and sampler, and the path tracer.
    if (scene->sensors.empty()) {
        auto obj = inst.create(ObjectKind::Sensor, Properties("perspective", xml.location));
        obj->plugin = "perspective";
        obj->location = xml.location;
        scene->sensors.push_back(as<Sensor>(obj, ObjectKind::Sensor));
    }
    scene->sensor = scene->sensors.front();
    if (!scene->integrator) {
        auto obj = inst.create(ObjectKind::Integrator, Properties("path", xml.location));
        obj->plugin = "path";
        obj->location = xml.location;
        scene->integrator = as<const IntegratorSettings>(obj, ObjectKind::Integrator);
    }
    scene->build();
    return scene;
}

} // namespace

std::unique_ptr<Scene> load_scene(const std::string& path,
                                  const std::map<std::string, std::string>& defines) {
    return build_scene(parse_xml_file(path, defines), path);
}

std::unique_ptr<Scene> load_scene_string(const std::string& xml, const std::string& base_dir,
                                         const std::map<std::string, std::string>& defines) {
    return build_scene(parse_xml_string(xml, base_dir, defines), std::string());
}

} // namespace penumbra
