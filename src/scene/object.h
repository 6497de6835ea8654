// Base class of every scene object created from a scene description.
#pragma once
#include "core/error.h"

#include <memory>
#include <string>
#include <vector>

namespace penumbra {

enum class ObjectKind { Shape, BSDF, Texture, Emitter, Sensor, Film, RFilter, Sampler, Integrator, Medium, Phase, Volume };

const char* kind_name(ObjectKind kind); // XML tag name: "shape", "bsdf", ...

class Object;

// Receives an object's differentiable parameters (Mitsuba 3's traverse()). Names are relative to the object.
class ParamVisitor {
public:
    virtual ~ParamVisitor() = default;
    // `size` floats at `values`; the object evaluates them through `*index` (first parameter index, -1 when
    // not differentiated; see core/param.h). `geometry` marks values that change the BVH (vertex positions).
    virtual void put(const std::string& name, float* values, int size, int* index, bool geometry = false) = 0;
    // An array of values with its shape (e.g. {H, W, 3} for an image, {N, 3} for vertex positions); visitors
    // that do not need the shape see put() with the flattened size.
    virtual void put_array(const std::string& name, float* values, const std::vector<int>& shape, int* index,
                           bool geometry = false) {
        int size = 1;
        for (int n : shape)
            size *= n;
        put(name, values, size, index, geometry);
    }
    // A nested object (texture, BSDF, emitter) whose own parameters are named `name.<param>`.
    virtual void put_object(const std::string& name, Object* object) = 0;
};

class Object {
public:
    virtual ~Object() = default;
    // Lists the differentiable parameters; objects without any keep the default.
    virtual void traverse(ParamVisitor&) {}
    // Called after values listed by traverse() were written from outside (Mitsuba's parameters_changed):
    // objects with derived data (a grid's majorants) refresh it; throws Error for values they cannot take.
    virtual void parameters_changed() {}
    virtual ObjectKind kind() const = 0;
    virtual std::string to_string() const { return std::string(kind_name(kind())) + "[" + plugin + "]"; }
    std::string id;       // the XML `id` attribute (may be empty)
    std::string plugin;   // the XML `type` attribute, e.g. "diffuse"
    SourceLocation location;
};

} // namespace penumbra
