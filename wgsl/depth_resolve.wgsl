// A multisampled depth attachment resolved for an XR compositor's depth layer: each
// pixel takes its nearest sample (the least depth: wgpu's depth runs from 0 at the near
// plane to 1 at the far one), so that reprojection moves an edge pixel with the surface
// in front, never with the one behind it. One triangle covers the target; the depth is
// written as the fragment's depth into a single-sampled Depth32Float attachment
// (src/compositor.rs).

@vertex
fn vs_main(@builtin(vertex_index) index: u32) -> @builtin(position) vec4<f32> {
    let corner = vec2<f32>(f32((index << 1u) & 2u), f32(index & 2u));
    return vec4<f32>(corner * 2.0 - 1.0, 0.0, 1.0);
}

@fragment
fn fs_main(@builtin(position) position: vec4<f32>) -> @builtin(frag_depth) f32 {
    let pixel = vec2<i32>(position.xy);
    var nearest = 1.0;
    for (var s = 0; s < i32(textureNumSamples(depth)); s++) {
        nearest = min(nearest, textureLoad(depth, pixel, s));
    }
    return nearest;
}
