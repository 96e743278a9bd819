#!/usr/bin/env bash
# Regenerate screenshots/views/: every mode and error map of three presets at a near-grazing view.
# Usage: bash scripts/screenshots.sh   (uses the release build; ~40 minutes on llvmpipe with 2 cores (13 per preset), seconds on a GPU)
set -euo pipefail
cd "$(dirname "$0")/.."
cargo build --release -q
for preset in default moss dirt-in-crevices; do
    ./target/release/lodestone --preset "presets/$preset.ron" render --mode all --formats png \
        --view-deg 70 --light-deg 50 --light-azimuth-deg 120 --distance 8 --size 480x270 --spp 256 \
        --out "screenshots/views/$preset" | tee "screenshots/views/$preset.txt"
done
# The curved object (default preset on a cylinder, seen side-on).
./target/release/lodestone render --mode all --formats png --shape cylinder --radius 1.5 \
    --view-deg 75 --view-azimuth-deg 90 --light-deg 40 --light-azimuth-deg 150 --distance 7 \
    --size 320x180 --spp 128 --out screenshots/views/cylinder | tee screenshots/views/cylinder.txt
# Lossless recompression keeps the repository small (pixels and colour chunks unchanged).
if command -v optipng >/dev/null; then
    find screenshots -name '*.png' -newer scripts/screenshots.sh -print0 | xargs -0 -r optipng -quiet -o2
fi
