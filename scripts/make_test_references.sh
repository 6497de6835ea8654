#!/usr/bin/env bash
# Regenerates the stored central-difference references of the boundary, light-motion, instancing and war
# environment tests (tests/data/fd/suite.json, read by tests/stored_reference.h): for every scene of the
# manifest, with its -D defines, `penumbra ad-suite --fd-only` at the scene's ci_res writes NAME_fd.exr,
# NAME_fd_stderr.exr and the key NAME_fd.json (seed 2, 16 batches, ci_fd_spp samples per pixel and side,
# stratified).
# Run from the repository root after building build/penumbra:
#     scripts/make_test_references.sh            # every scene
#     scripts/make_test_references.sh shadow_sky # only these
# A test names its reference and the same defines, in the same order (the key compares them).
set -euo pipefail
penumbra=${PENUMBRA:-build/penumbra}
manifest=tests/data/fd/suite.json
cache=tests/data/fd

# reference NAME RES [DEFINE...]
reference() {
  local name=$1 res=$2
  shift 2
  if [[ ${only:-} && " $only " != *" $name "* ]]; then return; fi
  local defines=()
  for d in "$@"; do defines+=(-D "$d"); done
  "$penumbra" ad-suite --manifest "$manifest" --res "$res" --only "$name" ${defines[@]+"${defines[@]}"} \
    --fd-only --cache "$cache" -q
}

only="$*"
reference silhouette_rotate 32 light=area
reference silhouette_rotate_2h 32 light=area
reference silhouette_translate 32 light=area
reference silhouette_translate_2h 32 light=area
reference shadow_point 32 light=point
reference shadow_point_2h 32 light=point
reference shadow_directional 32 light=directional
reference shadow_directional_2h 32 light=directional
reference shadow_sky 24 light=sky occluder_height=0.6
reference glossy_shadow 32 light=area
reference pixel_edges_translate 32
reference bulb_translate 32 light=point
reference bulb_translate_2h 32 light=point
reference sun_rotate 32 light=directional
reference sun_rotate_2h 32 light=directional
reference shadow_projector 32 light=projector
reference shadow_projector_2h 32 light=projector
reference tessellated_sphere_light 24 light=sphere
reference tessellated_rectangle_light 24 light=rectangle
reference instance_translate 32
reference instance_translate_2h 32
reference instance_vertices 32
reference instance_vertices_2h 32
reference rectangle_over_environment 16
reference contact_slide 32
reference contact_slide_2h 32
reference contact_turn 32
reference contact_turn_2h 32
reference contact_line 128 max_depth=3 crop_x=40 crop_y=80 crop_width=56 crop_height=16
reference contact_line_2h 128 max_depth=3 crop_x=40 crop_y=80 crop_width=56 crop_height=16
reference contact_hover 128 height=0.35 crop_x=40 crop_y=80 crop_width=56 crop_height=16
reference contact_hover_2h 128 height=0.35 crop_x=40 crop_y=80 crop_width=56 crop_height=16
reference stack_lower_slide 32
reference stack_lower_slide_2h 32
reference stack_lower_turn 32
reference stack_lower_turn_2h 32
reference stack_upper_slide 32
reference stack_upper_slide_2h 32
reference stack_upper_turn 32
reference stack_upper_turn_2h 32
reference stack_ball_slide 32
reference stack_ball_slide_2h 32
reference mirror_turn 16
reference mirror_turn_2h 16
reference mirror_reflectance 16
reference glass_ball_slide 16
reference glass_ball_slide_2h 16
reference mirror_turn_inner 16 crop_x=4 crop_y=6 crop_width=8 crop_height=6
reference mirror_turn_inner_2h 16 crop_x=4 crop_y=6 crop_width=8 crop_height=6
reference murky_ball_slide 16 crop_x=4 crop_y=4 crop_width=8 crop_height=8
reference murky_ball_slide_2h 16 crop_x=4 crop_y=4 crop_width=8 crop_height=8
