#!/usr/bin/env bash
# Golden outputs: proof that a restructuring changed no result. Runs a fixed list of commands — every
# integrator's render, every derivative method's forward derivative (with standard errors and, for psdr, its
# terms) and reverse gradient, on small scenes, with 1 and with 2 threads — and prints one line per output
# file: its name and the SHA-256 of its bytes (the gradient JSON without its timing).
#
#   scripts/golden.sh record golden.txt     # before a change: record the hashes of this build
#   scripts/golden.sh check golden.txt      # after it: every output byte-identical, or the list that differs
#
# BUILD (default build/) names the build tree whose `penumbra` runs. Hashes are a property of one machine and
# one build (Embree picks its kernels by CPU): record and check on the same machine, not across machines.
set -euo pipefail
cd "$(dirname "$0")/.."
mode=${1:-}
file=${2:-}
[ "$mode" = record ] || [ "$mode" = check ] || { echo "usage: scripts/golden.sh record|check FILE" >&2; exit 2; }
[ -n "$file" ] || { echo "usage: scripts/golden.sh record|check FILE" >&2; exit 2; }
bin="${BUILD:-build}/penumbra"
[ -x "$bin" ] || { echo "no $bin: build first (or set BUILD)" >&2; exit 2; }
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT

# name | command (arguments of `penumbra`; @O is the output prefix of this run, @T the threads)
jobs=(
  # Every integrator, surfaces and media.
  "render_path|render scenes/cbox/cbox.xml -D res=24 --spp 8 --integrator path -o @O.exr"
  "render_direct|render scenes/cbox/cbox.xml -D res=24 --spp 8 --integrator direct -o @O.exr"
  "render_bdpt|render scenes/cbox/cbox.xml -D res=24 --spp 8 --integrator bdpt -o @O.exr"
  "render_ptracer|render scenes/cbox/cbox.xml -D res=24 --spp 8 --integrator ptracer -o @O.exr"
  "render_volpath|render scenes/media/hazy_room.xml -D width=32 -D height=24 --spp 8 --integrator volpath -o @O.exr"
  "render_volpathmis|render scenes/media/hazy_room.xml -D width=32 -D height=24 --spp 8 --integrator volpathmis -o @O.exr"
  "render_bdpt_media|render scenes/media/hazy_room.xml -D width=32 -D height=24 --spp 8 --integrator bdpt -o @O.exr"
  "render_ptracer_media|render scenes/media/hazy_room.xml -D width=32 -D height=24 --spp 8 --integrator ptracer -o @O.exr"
  "render_volpath_translucent|render scenes/validation/translucent.xml -D res=24 --spp 8 -o @O.exr"
  "render_bdpt_bumpy|render scenes/validation/bumpy_sphere.xml -D res=24 --spp 8 -o @O.exr"
  "render_sppm|render scenes/sppm/caustic.xml -D res=24 -D photons=20000 -D passes=4 -o @O.exr"
  "render_sppm_fog|render scenes/sppm/fog_box.xml -D res=24 -D photons=10000 -D passes=4 -o @O.exr"
  # Forward mode: every method, surfaces and media, boundary terms and their split.
  "fd_shadow|fd scenes/validation/shadow.xml -D res=24 --param occluder.translate=1,0,0 --eps 1e-2 --spp 8 -o @O.exr"
  "interior_shadow|derivative scenes/validation/shadow.xml -D res=24 --param occluder.translate=1,0,0 --method interior --spp 16 -o @O.exr --stderr @O_se.exr --batches 2"
  "psdr_shadow|derivative scenes/validation/shadow.xml -D res=24 --param occluder.translate=1,0,0 --spp 32 -o @O.exr --stderr @O_se.exr --batches 2 --terms @O_term"
  "psdr_silhouette|derivative scenes/validation/silhouette.xml -D res=24 --param box.translate=1,0,0 --spp 32 -o @O.exr --terms @O_term"
  "psdr_moving_light|derivative scenes/validation/moving_light.xml -D res=24 --param lamp.translate=1,0,0 --spp 32 -o @O.exr --terms @O_term"
  "psdr_self_shadow|derivative scenes/validation/self_shadow.xml -D res=24 --param lshape.rotate=0,1,0 --spp 32 -o @O.exr --terms @O_term"
  "psdr_pixel_edges|derivative scenes/validation/pixel_edges.xml -D res=24 --param cam.translate=1,0,0 --spp 32 -o @O.exr --terms @O_term"
  "psdr_glossy_shadow|derivative scenes/validation/glossy_shadow.xml -D res=24 --param cube.translate=1,0,0 --spp 32 -o @O.exr --terms @O_term"
  "psdr_medium_scale|derivative scenes/validation/medium_params.xml -D res=16 --param smoke.scale --spp 16 -o @O.exr"
  "psdr_branches|derivative scenes/validation/branches.xml -D res=16 --param branches.rotate=0,1,0 --spp 16 -o @O.exr --terms @O_term"
  "psdr_bumpy_bdpt|derivative scenes/validation/bumpy_sphere.xml -D res=16 --param sphere.translate=1,0,0 --spp 16 -o @O.exr"
  "psdr_translucent|derivative scenes/validation/translucent.xml -D res=16 --param blob.translate=1,0,0 --spp 16 -o @O.exr"
  "psdr_deform|derivative scenes/validation/deform.xml -D res=16 --param blob.deform=1,0,0 --spp 16 -o @O.exr"
  "paths_bsdf|derivative scenes/validation/sampling_glossy_floor.xml -D res=24 --param mat.alpha --method paths --sampling bsdf --spp 16 -o @O.exr"
  "paths_differential|derivative scenes/validation/sampling_glossy_floor.xml -D res=24 --param mat.alpha --method paths --sampling differential --spp 16 -o @O.exr --stderr @O_se.exr --batches 2"
  "was_cube|derivative scenes/was/cube.xml -D res=16 --param cube.translate=1,0,0 --method was --spp 8 -o @O.exr"
  "was_cube_unbiased|derivative scenes/was/cube.xml -D res=16 --param cube.translate=1,0,0 --method was --was-unbiased --spp 8 -o @O.exr"
  "war_moving_light|derivative scenes/validation/moving_light.xml -D res=16 --param lamp.translate=1,0,0 --method war --spp 8 -o @O.exr"
  "war_bdpt_star|derivative scenes/war/star_light.xml -D res=16 --param star.translate=1,0,0 --method war-bdpt --spp 8 -o @O.exr"
  "dpm_c_reflector|derivative scenes/dpm/reflector.xml -D res=16 -D photons=5000 --param reflector.rotate@2,1.5,0=0,1,0 --method dpm-c --spp 4 -o @O.exr"
  "dpm_g_reflector|derivative scenes/dpm/reflector.xml -D res=16 -D photons=5000 --param light.translate=1,0,0 --method dpm-g --spp 4 -o @O.exr"
  # Reverse mode: every method's gradient against a fixed target (rendered here, hashed too).
  "target_shadow|render scenes/validation/shadow.xml -D res=24 -D occluder_height=3.0 --spp 8 --seed 7 -o @O.exr"
  "target_glossy|render scenes/validation/sampling_glossy_floor.xml -D res=24 -D alpha=0.3 --spp 8 --seed 7 -o @O.exr"
  "target_cube|render scenes/was/cube.xml -D res=16 --spp 8 --seed 7 -o @O.exr"
  "target_moving_light|render scenes/validation/moving_light.xml -D res=16 --spp 8 --seed 7 -o @O.exr"
  "target_star|render scenes/war/star_light.xml -D res=16 --spp 8 --seed 7 -o @O.exr"
  "target_reflector|render scenes/dpm/reflector.xml -D res=16 -D photons=5000 -D passes=4 --seed 7 -o @O.exr"
  "target_branches|render scenes/validation/branches.xml -D res=16 --spp 8 --seed 7 -o @O.exr"
  "grad_interior|gradient scenes/validation/shadow.xml -D res=24 --param occluder.translate=1,0,0 --method interior --spp 16 --target @W/target_shadow_@T.exr -o @O.json"
  "grad_psdr|gradient scenes/validation/shadow.xml -D res=24 --param occluder.translate=1,0,0 --spp 32 --target @W/target_shadow_@T.exr -o @O.json"
  "grad_psdr_media|gradient scenes/validation/branches.xml -D res=16 --param branches.rotate=0,1,0 --spp 16 --target @W/target_branches_@T.exr -o @O.json"
  "grad_paths|gradient scenes/validation/sampling_glossy_floor.xml -D res=24 --param mat.alpha --method paths --sampling differential --spp 16 --target @W/target_glossy_@T.exr -o @O.json"
  "grad_was|gradient scenes/was/cube.xml -D res=16 --param cube.translate=1,0,0 --method was --spp 8 --target @W/target_cube_@T.exr -o @O.json"
  "grad_war|gradient scenes/validation/moving_light.xml -D res=16 --param lamp.translate=1,0,0 --method war --spp 8 --target @W/target_moving_light_@T.exr -o @O.json"
  "grad_war_bdpt|gradient scenes/war/star_light.xml -D res=16 --param star.translate=1,0,0 --method war-bdpt --spp 8 --target @W/target_star_@T.exr -o @O.json"
  "grad_dpm_c|gradient scenes/dpm/reflector.xml -D res=16 -D photons=5000 --param light.translate=1,0,0 --method dpm-c --spp 4 --target @W/target_reflector_@T.exr -o @O.json"
  "grad_dpm_g_matching|gradient scenes/dpm/reflector.xml -D res=16 -D photons=5000 --param light.translate=1,0,0 --method dpm-g --spp 4 --target @W/target_reflector_@T.exr --loss matching -o @O.json"
)

out=$work/hashes.txt
: >"$out"
for threads in 1 2; do
  for job in "${jobs[@]}"; do
    name=${job%%|*}
    args=${job#*|}
    prefix=$work/${name}_$threads
    args=${args//@O/$prefix}
    args=${args//@W/$work}
    args=${args//@T/$threads}
    [[ $args == *--seed* ]] || args="$args --seed 1"
    # shellcheck disable=SC2086
    if ! "$bin" $args --threads "$threads" -q >"$work/log" 2>&1; then
      echo "golden: '$name' failed (threads $threads):" >&2
      cat "$work/log" >&2
      exit 1
    fi
    for f in "$prefix"*; do
      case $f in
        *.json) hash=$(python3 -c 'import json,sys; d=json.load(open(sys.argv[1])); d.pop("seconds",None); print(json.dumps(d,sort_keys=True))' "$f" | sha256sum) ;;
        *) hash=$(sha256sum <"$f") ;;
      esac
      echo "$(basename "$f") ${hash%% *}" >>"$out"
    done
  done
done

if [ "$mode" = record ]; then
  cp "$out" "$file"
  echo "golden: $(wc -l <"$out") outputs recorded in $file"
else
  if diff <(sort "$file") <(sort "$out") >"$work/diff"; then
    echo "golden: all $(wc -l <"$out") outputs byte-identical"
  else
    echo "golden: outputs that differ (< recorded, > now):"
    cat "$work/diff"
    exit 1
  fi
fi
