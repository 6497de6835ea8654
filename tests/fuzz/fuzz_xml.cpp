// Mitsuba XML scenes: parsed and instantiated (every plugin's factory, mesh and texture loaders, the Embree
// scene), never rendered. Relative file names resolve against the fixture directory, so that <include>,
// meshes, textures, grids and spectra can be reached.
#include "fuzz_targets.h"

#include "scene/scene.h"

namespace penumbra::fuzz {

void fuzz_xml(const uint8_t* data, size_t size) {
    const std::string& dir = fixture_dir();
    const std::string xml(reinterpret_cast<const char*>(data), size);
    reject_with_exceptions([&] { load_scene_string(xml, dir); });
}

} // namespace penumbra::fuzz
