// Mirror of `core/src/microfacet/slopes.rs`, function for function under the same names.
// `//#if feature` blocks are stripped by render/src/specialize.rs when a scene does not use the feature.

fn slope_of(n: vec3<f32>) -> vec2<f32> {
    return vec2<f32>(-n.x, -n.y) / max(n.z, 1e-30);
}

fn normal_of(s: vec2<f32>) -> vec3<f32> {
    return normalize(vec3<f32>(-s.x, -s.y, 1.0));
}
