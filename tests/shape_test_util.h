// Projected (silhouette) area of shapes measured by rendering: black shapes in front of a white constant
// environment, seen by an orthographic camera looking along +y at the square [-2, 2]^2 of the xz plane
// (film area 16). Each pixel's expected value (box filter) is the fraction of it left uncovered, so the
// area is 16 (1 - image mean); its standard error comes from independent batches.
#pragma once
#include "render_stats.h"
#include "scene/scene.h"

#include <string>

namespace penumbra::test {

struct ProjectedArea {
    double value = 0.0, stderr_value = 0.0;
};

inline std::string projected_area_scene(const std::string& shapes) {
    return R"(<scene version="3.0.0">
    <integrator type="path"><integer name="max_depth" value="1"/></integrator>
    <sensor type="orthographic">
        <transform name="to_world"><scale x="2" y="2"/><lookat origin="0,-5,0" target="0,0,0" up="0,0,1"/></transform>
        <film type="hdrfilm"><integer name="width" value="64"/><integer name="height" value="64"/>
            <rfilter type="box"/></film>
    </sensor>
    <emitter type="constant"><rgb name="radiance" value="1"/></emitter>
    <bsdf type="diffuse" id="black"><rgb name="reflectance" value="0"/></bsdf>
)" + shapes +
           "\n</scene>\n";
}

inline ProjectedArea projected_area(const Scene& scene, int batches = 8, int spp = 16) {
    const BatchStats s = render_batches(scene, batches, spp);
    return {16.0 * (1.0 - s.image_mean), 16.0 * s.image_mean_stderr};
}

} // namespace penumbra::test
