#!/bin/bash
# The reference of SPPM.ConvergesToBdptThroughMedia (tests/test_sppm.cpp): scenes/sppm/fog_box.xml at 32x32 by
# bdpt at 16384 spp (its own RMSE ~0.0005: bdpt at 4096 spp is 0.0012 from it). About 200 s on 2 cores.
set -euo pipefail
cd "$(dirname "$0")/.."
build/penumbra render scenes/sppm/fog_box.xml -D res=32 --integrator bdpt --spp 16384 --seed 7 \
    -o scenes/sppm/fog_box_ref32.exr
