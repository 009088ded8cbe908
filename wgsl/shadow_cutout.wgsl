// The frame's shadow pass for cutout bins (alphaMode MASK): as wgsl/shadow.wgsl, but
// each fragment reads its material's alpha and is discarded under the cutoff, so light
// passes through the holes the main pass cuts. Opaque bins keep the depth-only pipeline.
// Bindings: DRAW_BINDINGS (group 0) and the materials (group 1).

struct CutoutVertex {
    @builtin(position) clip: vec4<f32>,
    // Both sets of texture coordinates (xy, zw).
    @location(0) uvs: vec4<f32>,
    // The instance and its material.
    @location(1) @interpolate(flat) ids: vec2<u32>,
}

@vertex
fn vs_main(v: VertexInput, @builtin(instance_index) instance_index: u32) -> CutoutVertex {
    let d = decode(v, instance_index, 0u, false);
    return CutoutVertex(d.clip, vec4(d.uv, d.uv1), vec2(d.instance, d.material));
}

@fragment
fn fs_main(in: CutoutVertex) {
    let color = unpack4x8unorm(instances_at(in.ids.x).color);
    if (base_color_at(color, in.uvs, in.ids.y).a < materials[in.ids.y].alpha_cutoff) {
        discard;
    }
}
