#!/usr/bin/env bash
# The error tables of issue 6's closing note: `lodestone eval` (far, fully filtered patch; CPU
# reference evaluator; ground truth 40 000 eye rays) for each new colour/lighting term at views
# 0°–85°, and the [HNPN14 Fig. 14] experiment: a 1-D colour map of the slope's x component (t = n_x,
# the slope term's direction at elevation 0), low or high frequency, on a surface whose slopes are
# Gaussian (identity transfer) or not (a terrace-like transfer curve), both with 8² and 16² nodes.
# Usage: bash scripts/slope_terms_eval.sh [SPP]   (about 10 minutes on 2 cores)
set -euo pipefail
cd "$(dirname "$0")/.."
spp=${1:-40000}
cargo build --release -q
bin=./target/release/lodestone
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT

# One material per term, from the shipped presets.
# slope colour alone under the sun: the snow preset without its sky
python3 - "$tmp" <<'PY'
import re, sys, pathlib
tmp = pathlib.Path(sys.argv[1])
snow = pathlib.Path("presets/snow-under-sky.ron").read_text()
light = re.search(r"    lighting: \(.*?\n    \),\n", snow, re.S).group(0)
(tmp / "slope.ron").write_text(snow.replace(light, "    lighting: (sun: 1.0, environment: None),\n").replace('"Snow under sky"', '"Slope colour (snow), sun only"'))
(tmp / "env.ron").write_text(pathlib.Path("presets/default.ron").read_text().rstrip().rstrip(")") +
    "    lighting: (sun: 0.0, environment: Some((source: Sky(()), intensity: 1.0))),\n)\n")
(tmp / "env.ron").write_text((tmp / "env.ron").read_text().replace('"Rusty bumps"', '"Rusty bumps under the sky only"'))
# Fig. 14: map of n_x, low / high frequency, Gaussian / non-Gaussian slopes.
low = "[(position: -0.8, color: (0.05, 0.05, 0.05)), (position: 0.8, color: (0.9, 0.9, 0.9))]"
stripes = ", ".join(f"(position: {-0.6 + 0.15 * i:.2f}, color: ({c}, {c}, {c}))" for i, c in enumerate([0.05, 0.9] * 4 + [0.05]))
high = f"[{stripes}]"
terraces = re.search(r"transfer: (Curve\(Curve\(.*?\)\))", pathlib.Path("presets/terraces.ron").read_text(), re.S).group(1)
for slopes_name, transfer in [("gaussian", "Identity"), ("non-gaussian", terraces)]:
    for freq, stops in [("low", low), ("high", high)]:
        for n in [8, 16]:
            (tmp / f"fig14-{slopes_name}-{freq}-{n}.ron").write_text(f"""Material(
    version: 1,
    name: "Fig. 14: {slopes_name} slopes, {freq}-frequency map of n_x, {n}x{n} nodes",
    driver: Noise((seed: 3, components: 48, octaves: 2, gain: 0.5, bandwidth: 0.3, frequency: 1.0)),
    heights: (sigma_h: 0.05, transfer: {transfer}),
    slopes: (sigma_nx: 0.35, sigma_ny: 0.35),
    color: Gradient(map: (stops: [(position: -2.0, color: (0.5, 0.5, 0.5)), (position: 2.0, color: (0.5, 0.5, 0.5))], interpolation: Linear), source: Driver),
    terms: (mode: Linear, constant: None, height: None, slope: Some((color: (map: (stops: {stops}, interpolation: Linear), elevation_deg: 0.0, azimuth_deg: 0.0), weight: 1.0))),
    brdf: (albedo: 1.0, specular: 0.0, roughness: 0.2),
    lighting: (sun: 0.0, environment: Some((source: Sky((zenith: (1.0, 1.0, 1.0), horizon: (1.0, 1.0, 1.0), ground: (1.0, 1.0, 1.0), sun: (0.0, 0.0, 0.0))), intensity: 1.0))),
    filtering: (slope_points: {n}),
)
""")
PY

row() { # preset view -> "naive vi filtered" max relative errors
    "$bin" --preset "$1" eval --view-deg "$2" --light-deg 30 --light-azimuth-deg 90 --spp "$spp" --json |
        python3 -c 'import json,sys
d = json.load(sys.stdin); gt = d["ground_truth"]
err = lambda v: max(abs(a - b) / b for a, b in zip(v, gt))
print(" | ".join(f"{100 * err(d[k]):.1f}%" for k in ("naive", "view_independent", "filtered")))'
}
for p in "$tmp/slope.ron" "$tmp/env.ron" presets/snow-under-sky.ron presets/snake-skin.ron; do
    echo
    echo "$(grep -m1 'name:' "$p" | sed 's/.*name: "\(.*\)".*/\1/')"
    echo "| view | naive | view-independent | filtered |"
    echo "|---|---|---|---|"
    for v in 0 30 60 75 85; do echo "| ${v}° | $(row "$p" $v) |"; done
done
echo
echo "Fig. 14 (uniform white sky, no sun: the radiance is the albedo-weighted mean of the map over D_s)"
echo "| slopes | map | nodes | 0° | 60° | 80° |"
echo "|---|---|---|---|---|---|"
for s in gaussian non-gaussian; do for f in low high; do for n in 8 16; do
    p="$tmp/fig14-$s-$f-$n.ron"
    e() { row "$p" "$1" | awk -F' [|] ' '{print $3}'; }
    echo "| $s | $f | ${n}² | $(e 0) | $(e 60) | $(e 80) |"
done; done; done
