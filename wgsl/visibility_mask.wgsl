// The lens's hidden area written to depth before a display's scene (src/draw/mask.rs):
// each view's hidden triangles, already placed in the display's target, at depth 0 (the
// near plane), so that every later fragment there fails the depth test and is never
// shaded. Color is not written. One draw covers the display: side by side, one instance
// per view; in multiview the view index picks the view's triangles. A view's unused
// vertices have w = 0 and fall outside every clip volume.

@vertex
fn vs_main(
    @builtin(vertex_index) vertex: u32,
    @builtin(instance_index) instance: u32,
// MULTIVIEW_VIEW_INDEX
) -> @builtin(position) vec4<f32> {
    let p = mask.vertices[VIEW * MASK_VERTICES + vertex];
    return vec4<f32>(p.xy, 0.0, p.w);
}

@fragment
fn fs_main() -> @location(0) vec4<f32> {
    return vec4<f32>(0.0);
}
