#!/usr/bin/env bash
# Regenerates the finite-difference references of the DPM-C validation scenes (scenes/dpm/,
# docs/dpm-validation.md) in tests/data/dpm/: for every scene a primal render, and for every parameter the
# central difference (I(θ + h) − I(θ − h)) / 2h with common random numbers (both sides trace the same
# eye samples and photon streams) and its per-pixel standard error over independent batches; and the egg
# demo's expected image at its solution, the target of DpmDemos.EggMatchingGradientVanishesAtTheSolution.
# Run from the repository root after building build/penumbra:
#     scripts/make_dpm_references.sh
# The meshes (scenes/dpm/*.obj) are regenerated first; their scripts are deterministic.
set -euo pipefail
penumbra=${PENUMBRA:-build/penumbra}
python=${PYTHON:-/usr/bin/python3}
out=tests/data/dpm
seed=900001  # apart from the tests' seeds (1 + 1000 · PENUMBRA_TEST_SEED): references and tests independent
spp=256      # sppm passes in total (one eye sample per pixel and photon_count photons per pass)
batches=16   # independent batches of spp / batches passes for the standard errors
mkdir -p "$out"

(cd scenes/dpm && "$python" make_reflector.py && "$python" make_slab.py)

# primal SCENE NAME: the image at the scene's defaults (32x32) with the references' passes and seed.
primal() {
  "$penumbra" render "scenes/dpm/$1.xml" --spp "$spp" --seed "$seed" -q -o "$out/$2.exr"
}

# reference SCENE NAME PARAM H: the derivative image NAME.exr and its standard error NAME_stderr.exr.
reference() {
  "$penumbra" fd "scenes/dpm/$1.xml" --param "$3" --eps "$4" --spp "$spp" --batches "$batches" \
    --seed "$seed" -q -o "$out/$2.exr" --stderr "$out/$2_stderr.exr"
}

primal reflector reflector_primal
reference reflector reflector_rotate_y 'reflector.rotate@2,1.5,0=0,1,0' 0.002
reference reflector reflector_light_x 'light.translate=1,0,0' 0.005

primal slab slab_primal
reference slab slab_thickness 'slab_top.translate=0,1,0' 0.01
reference slab slab_bulge 'slab_top.deform@0.15,2.2,-0.1=0,1,0' 0.003

# The egg demo at its solution (light height 1.6), 32², 1024 passes of 20,000 photons: the expected image the
# matching-gradient test matches against (at a fixed radius the expectation does not depend on the photons).
"$penumbra" render scenes/dpm/egg/scene.xml -D res=32 -D photons=20000 -D radius=0.012 -D light_y=1.6 \
  --spp 1024 --seed "$seed" -q -o "$out/egg_solution.exr"
