// Base class of every scene object created from a scene description.
#pragma once
#include "core/error.h"

#include <memory>
#include <string>

namespace penumbra {

enum class ObjectKind { Shape, BSDF, Texture, Emitter, Sensor, Film, RFilter, Sampler, Integrator, Medium, Phase };

const char* kind_name(ObjectKind kind); // XML tag name: "shape", "bsdf", ...

class Object {
public:
    virtual ~Object() = default;
    virtual ObjectKind kind() const = 0;
    virtual std::string to_string() const { return std::string(kind_name(kind())) + "[" + plugin + "]"; }
    std::string id;       // the XML `id` attribute (may be empty)
    std::string plugin;   // the XML `type` attribute, e.g. "diffuse"
    SourceLocation location;
};

} // namespace penumbra
