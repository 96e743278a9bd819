#!/usr/bin/env bash
# Regenerate screenshots/presets/: one thumbnail per preset (the filtered view, 240×160, camera 65° from
# the normal at distance 4, light 40° at azimuth 115°). Seconds on a GPU, about a minute on llvmpipe.
# Usage: bash scripts/thumbnails.sh
set -euo pipefail
cd "$(dirname "$0")/.."
cargo build --release -q
mkdir -p screenshots/presets
for f in presets/*.ron; do
    name=$(basename "$f" .ron)
    ./target/release/lodestone --preset "$f" render --mode filtered --view-deg 65 --distance 4 \
        --light-deg 40 --light-azimuth-deg 115 --size 240x160 --out "screenshots/presets/$name.png"
done
