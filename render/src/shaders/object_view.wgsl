// The object view's compute pass (GPU only): one cone per pixel from the camera in `object`
// (ObjectParams), traced through the voxel field (cone_trace.wgsl), written as linear RGB and
// coverage; pixels whose loops the adapter cut are counted in `object_cut`.

// GPU only: 2, as a value the shader compiler cannot fold (note_budget).
fn object_two() -> u32 {
    return object.two;
}

// GPU only: the compute entry point.
@compute @workgroup_size(8, 8)
fn object_main(@builtin(global_invocation_id) id: vec3<u32>) {
    if (id.x >= object.width || id.y >= object.height) {
        return;
    }
    loop_cut = false;
    let p = vec2<f32>(f32(id.x) + 0.5, f32(id.y) + 0.5);
    let raw = object.dir00 + object.step_x * p.x + object.step_y * p.y;
    let cone = Cone(object.eye, normalize(raw), 0.0, object.spread, object.lens, object.focus);
    let px = trace(cone, object.mode);
    note_budget(object_two());
    if (loop_cut) {
        atomicAdd(&object_cut[0], 1u);
    }
    object_out[id.y * object.width + id.x] = px;
}
