// Every scene of Mitsuba 3's documentation (mitsuba-data/docs/scenes/**.xml, without the include/ fragments)
// either loads and renders at 1 spp, or fails with one line naming the first unsupported plugin the loader meets
// (children are instantiated before their parent, top-level objects in document order; a parse-time <volume>
// comes first of all).
// Runtime: dominated by ~55 full-size (mostly 960x720) 1-spp renders, about 1-2 s each on 2 cores.
#include "render/render.h"
#include "scene/scene.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <set>

using namespace penumbra;
namespace fs = std::filesystem;

namespace {

struct DocScene {
    const char* file;
    const char* kind; // "" = supported; else the XML tag of the unsupported plugin, "parameter" or "file"
    const char* type; // the unsupported plugin type, parameter name, or the file that cannot be found
};

// Printed by ctest/gtest when naming a case: the file name, not the struct's bytes.
void PrintTo(const DocScene& scene, std::ostream* os) { *os << scene.file; }

// Worked out by reading each file (and its includes): plugins outside penumbra's set make a scene
// unsupported.
const DocScene kScenes[] = {
    {"bsdf_blendbsdf.xml", "", ""},
    {"bsdf_bumpmap_with.xml", "", ""},
    {"bsdf_bumpmap_without.xml", "", ""},
    {"bsdf_conductor_aluminium.xml", "", ""},
    {"bsdf_conductor_gold.xml", "", ""},
    {"bsdf_dielectric_diamond.xml", "", ""},
    {"bsdf_dielectric_glass.xml", "", ""},
    {"bsdf_diffuse_plain.xml", "", ""},
    {"bsdf_diffuse_textured.xml", "", ""},
    {"bsdf_hair_blonde.xml", "bsdf", "hair"},
    {"bsdf_hair_brown.xml", "bsdf", "hair"},
    {"bsdf_mask_after.xml", "", ""},
    {"bsdf_mask_before.xml", "", ""},
    {"bsdf_measured_polarized_fakegold.xml", "bsdf", "measured_polarized"},
    {"bsdf_measured_polarized_fakegold_stokes.xml", "bsdf", "measured_polarized"},
    {"bsdf_measured_polarized_gold.xml", "bsdf", "measured_polarized"},
    {"bsdf_measured_polarized_gold_stokes.xml", "bsdf", "measured_polarized"},
    {"bsdf_normalmap_with.xml", "", ""},
    {"bsdf_normalmap_without.xml", "", ""},
    {"bsdf_plastic_default.xml", "", ""},
    {"bsdf_plastic_diffuse.xml", "", ""},
    {"bsdf_plastic_nopreserve.xml", "", ""},
    {"bsdf_plastic_preserve.xml", "", ""},
    {"bsdf_plastic_shiny.xml", "", ""},
    {"bsdf_polarizer_absorbing.xml", "bsdf", "polarizer"},
    {"bsdf_polarizer_aligned.xml", "bsdf", "polarizer"},
    {"bsdf_polarizer_middle.xml", "bsdf", "polarizer"},
    {"bsdf_pplastic.xml", "bsdf", "pplastic"},
    {"bsdf_pplastic_diffuse.xml", "bsdf", "pplastic"},
    {"bsdf_pplastic_diffuse_stokes.xml", "bsdf", "pplastic"},
    {"bsdf_pplastic_specular.xml", "bsdf", "pplastic"},
    {"bsdf_pplastic_specular_stokes.xml", "bsdf", "pplastic"},
    {"bsdf_roughconductor_anisotropic_aluminium.xml", "", ""},
    {"bsdf_roughconductor_copper.xml", "", ""},
    {"bsdf_roughconductor_textured_carbon.xml", "", ""},
    {"bsdf_roughdielectric_glass.xml", "", ""},
    {"bsdf_roughdielectric_rough.xml", "", ""},
    {"bsdf_roughdielectric_textured.xml", "", ""},
    {"bsdf_roughplastic_beckmann.xml", "", ""},
    {"bsdf_roughplastic_diffuse.xml", "", ""},
    {"bsdf_roughplastic_ggx.xml", "", ""},
    {"bsdf_roughplastic_nopreserve.xml", "", ""},
    {"bsdf_roughplastic_preserve.xml", "", ""},
    {"bsdf_thindielectric_glass.xml", "", ""},
    {"bsdf_twosided_cbox.xml", "", ""},
    {"bsdf_twosided_cbox_onesided.xml", "", ""},
    {"emitter_projector_constant.xml", "", ""},
    {"emitter_projector_textured.xml", "", ""},
    {"emitter_spot_no_texture.xml", "", ""},
    {"emitter_spot_texture.xml", "", ""},
    {"integrator_aov.xml", "", ""},
    {"integrator_depth_1.xml", "", ""},
    {"integrator_depth_2.xml", "", ""},
    {"integrator_depth_3.xml", "", ""},
    {"integrator_depth_inf.xml", "", ""},
    {"integrator_direct_both.xml", "", ""},
    {"integrator_direct_bsdf.xml", "", ""},
    {"integrator_direct_lum.xml", "", ""},
    {"integrator_stokes_cbox.xml", "integrator", "stokes"},
    {"medium_homogeneous_sss.xml", "", ""},
    {"medium_homogeneous_sss_textured.xml", "volume", "gridvolume"},
    {"sampler_independent_16spp.xml", "", ""},
    {"sampler_independent_25spp.xml", "", ""},
    {"sampler_ldsampler_16spp.xml", "", ""},
    {"sampler_multijitter_16spp.xml", "", ""},
    {"sampler_orthogonal_25spp.xml", "", ""},
    {"sampler_stratified_16spp.xml", "", ""},
    // These two lack the <path value="../../common"/> of the others, so (as in Mitsuba) their meshes are not
    // found.
    {"sensor_orthographic.xml", "file", "meshes/matpreview.serialized"},
    {"sensor_orthographic_2.xml", "file", "meshes/cbox/cbox_luminaire.obj"},
    {"sensor_perspective.xml", "", ""},
    {"sensor_perspective_large_fov.xml", "", ""},
    {"sensor_thinlens.xml", "", ""},
    {"sensor_thinlens_small_aperture.xml", "", ""},
    {"shape_bsplinecurve_basic.xml", "", ""},
    {"shape_bsplinecurve_parameterization.xml", "", ""},
    {"shape_cylinder_onesided.xml", "", ""},
    {"shape_cylinder_twosided.xml", "", ""},
    {"shape_disk.xml", "", ""},
    {"shape_disk_parameterization.xml", "", ""},
    {"shape_linearcurve_basic.xml", "", ""},
    {"shape_linearcurve_parameterization.xml", "", ""},
    {"shape_ply_bunny.xml", "", ""},
    {"shape_ply_bunny_facet.xml", "", ""},
    {"shape_rectangle.xml", "", ""},
    {"shape_rectangle_parameterization.xml", "", ""},
    {"shape_sdfgrid.xml", "shape", "sdfgrid"}, // inside a shapegroup: the child fails first
    {"shape_sdfgrid_analytic.xml", "shape", "sdfgrid"},
    {"shape_sphere_basic.xml", "", ""},
    {"shape_sphere_light_analytic.xml", "", ""},
    {"shape_sphere_light_mesh.xml", "", ""},
    {"shape_sphere_parameterization.xml", "", ""},
    {"texture_checkerboard.xml", "", ""},
    {"texture_mesh_attribute_face.xml", "", ""},
    {"texture_mesh_attribute_vertex.xml", "", ""},
    {"variants_cbox_rgb.xml", "", ""},
    {"variants_cbox_spectral.xml", "", ""},
    // Written with capitalized plugin names ("Rectangle", "Sphere"), which penumbra matches case-insensitively.
    {"principled_blend_creation/scene.xml", "", ""},
    {"principled_blend_creation/scene_light.xml", "file", "studio.exr"}, // not shipped with the data
    {"principled_blend_creation/scene_studio.xml", "file", "studio.exr"},
    {"principled_blend_creation/scene_thin.xml", "", ""},
    {"principled_blend_creation/scene_thin_light.xml", "", ""},
};

const std::string kDir = PENUMBRA_SHARED_DIR "/mitsuba-data/docs/scenes";
// One sample per pixel keeps the whole suite fast; `res` shrinks the one scene whose film size is a
// parameter.
const std::map<std::string, std::string> kDefines = {{"spp", "1"}, {"res", "64"}};

class DocsScenes : public ::testing::TestWithParam<DocScene> {};

} // namespace

// Every scene file of the directory and its subdirectories, except the fragments that scenes <include>.
TEST(DocsScenesList, CoversEveryScene) {
    if (!fs::is_directory(kDir)) GTEST_SKIP() << "no Mitsuba docs scenes at " << kDir;
    std::set<std::string> listed;
    for (const DocScene& s : kScenes)
        listed.insert(s.file);
    for (const auto& entry : fs::recursive_directory_iterator(kDir)) {
        const std::string rel = fs::relative(entry.path(), kDir).generic_string();
        if (entry.path().extension() == ".xml" && rel.rfind("include/", 0) != 0) {
            EXPECT_TRUE(listed.count(rel)) << "scene not in the list: " << rel;
        }
    }
}

TEST_P(DocsScenes, LoadsAndRendersOrNamesTheUnsupportedPlugin) {
    if (!fs::is_directory(kDir)) GTEST_SKIP() << "no Mitsuba docs scenes at " << kDir;
    const DocScene& s = GetParam();
    const std::string path = kDir + "/" + s.file;
    if (std::string(s.kind).empty()) {
        std::unique_ptr<Scene> scene;
        ASSERT_NO_THROW(scene = load_scene(path, kDefines)) << s.file;
        ASSERT_TRUE(scene->sensor && scene->sensor->film && scene->integrator);
        RenderOptions opts;
        opts.spp = 1;
        const Image img = render(*scene, opts);
        EXPECT_EQ(img.width, scene->sensor->film->width);
        EXPECT_EQ(img.height, scene->sensor->film->height);
        EXPECT_EQ(img.pixels.size(), size_t(img.width) * size_t(img.height));
        size_t non_finite = 0;
        for (const Color3f& c : img.pixels)
            non_finite += is_finite(c) ? 0 : 1;
        EXPECT_EQ(non_finite, 0u) << s.file;
        return;
    }
    try {
        load_scene(path, kDefines);
        ADD_FAILURE() << s.file << " loaded, but should fail on " << s.kind << " '" << s.type << "'";
    } catch (const LoadError& e) {
        const std::string msg = e.what();
        EXPECT_EQ(msg.find('\n'), std::string::npos) << msg;
        EXPECT_NE(msg.find(".xml:"), std::string::npos) << "no file:line in: " << msg;
        const std::string kind = s.kind;
        const std::string expected = kind == "parameter" ? "'" + std::string(s.type) + "'"
                                     : kind == "file"    ? "'" + std::string(s.type) + "' not found"
                                                         : "unsupported " + kind + " plugin '" + s.type + "'";
        EXPECT_NE(msg.find(expected), std::string::npos) << "expected \"" << expected << "\" in: " << msg;
    }
}

INSTANTIATE_TEST_SUITE_P(Mitsuba, DocsScenes, ::testing::ValuesIn(kScenes),
                         [](const ::testing::TestParamInfo<DocScene>& info) {
                             std::string name = fs::path(info.param.file).replace_extension().generic_string();
                             for (char& c : name)
                                 if (!std::isalnum(static_cast<unsigned char>(c))) c = '_';
                             return name;
                         });
