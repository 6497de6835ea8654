#include "scene/texture.h"

namespace penumbra {

namespace {

// Walks nested objects (BSDFs, textures, emitters) until a texture matches.
class TextureSearch final : public ParamVisitor {
public:
    explicit TextureSearch(const std::function<bool(const Texture&)>& match) : match_(match) {}
    void put(const std::string&, float*, int, int*, bool) override {}
    void put_object(const std::string&, Object* object) override {
        if (!object || found) return;
        if (const auto* texture = dynamic_cast<const Texture*>(object); texture && match_(*texture)) found = true;
        else object->traverse(*this);
    }
    bool found = false;

private:
    const std::function<bool(const Texture&)>& match_;
};

} // namespace

bool has_texture(Object& object, const std::function<bool(const Texture&)>& match) {
    TextureSearch search(match);
    object.traverse(search);
    return search.found;
}

} // namespace penumbra
