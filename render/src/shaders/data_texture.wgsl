// The material's data as the views read it: a 2-D texture of its f32 words' bits (R32Uint),
// DATA_ROW words a row (renderer.rs `GpuMaterial`). llvmpipe loads a storage buffer at an index
// that is not a constant one lane at a time, in a branchy loop over its eight lanes (gallivm's
// emit_load_mem); a texel fetch is one branch-free gather there, and a GPU's texture path reads
// tables as well as its storage path. Replaces bindings.wgsl's storage block in the view shaders.
@group(0) @binding(1) var data_texels: texture_2d<u32>;

// Entry i of the material's data. GPU only.
fn datum(i: u32) -> f32 {
    return bitcast<f32>(textureLoad(data_texels, vec2<u32>(i & (DATA_ROW - 1u), i / DATA_ROW), 0).x);
}
