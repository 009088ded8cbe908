// The far layer into one stereo display's target, before its near geometry
// (src/far_layer.rs, src/renderer/display/far_layer.rs). One draw of two instances, the
// instance index the eye: a triangle over that eye's half, whose fragments take the far
// layer in the direction through their pixel (the eye's exact mapping at infinity),
// with that far point's depth as this eye sees it, so that near geometry drawn next
// hides it or is hidden by it as it should. Where the far layer holds nothing the
// fragment is discarded and the clear color stays.
// Bindings: FAR_COMPOSITE_BINDINGS in src/shaders/bindings.rs.

// The vertex stage: wgsl/shared/eye_halves.wgsl.

// The far layer's coordinates (0..1 from the top left) of the direction through pixel
// `pixel` of eye `eye` (pixels from its half's top left); outside 0..1 when the far
// layer does not hold it. The CPU twin is FarPlan::far_uv.
fn far_uv(eye: u32, pixel: vec2<f32>) -> vec3<f32> {
    let e = display.eye[eye];
    let size = display.resolution;
    let ndc = vec2(pixel.x / size.x * 2.0 - 1.0, 1.0 - pixel.y / size.y * 2.0);
    let on_far_plane = e.world_from_clip * vec4(ndc, 1.0, 1.0);
    let direction = on_far_plane.xyz / on_far_plane.w - e.position;
    let c = far.eye[0].clip_from_world * vec4(direction, 0.0);
    return vec3(c.x / c.w * 0.5 + 0.5, 0.5 - c.y / c.w * 0.5, c.w);
}

struct CompositeOutput {
    @location(0) color: vec4<f32>,
    @builtin(frag_depth) depth: f32,
}

@fragment
fn fs_main(in: EyeHalf) -> CompositeOutput {
    let pixel = vec2(in.position.x - f32(in.eye) * display.resolution.x, in.position.y);
    if (pixel.x < 0.0 || pixel.x >= display.resolution.x) {
        discard;
    }
    let at = far_uv(in.eye, pixel);
    if (at.z <= 0.0 || any(at.xy < vec2(0.0)) || any(at.xy > vec2(1.0))) {
        discard;
    }
    let texel = vec2<u32>(min(at.xy * far.resolution, far.resolution - 1.0));
    let depth = textureLoad(far_depth, texel, 0);
    if (depth >= 1.0) {
        discard;
    }
    let color = textureSampleLevel(far_color, far_sampler, at.xy, 0.0);
    let ndc = vec2(at.x * 2.0 - 1.0, 1.0 - at.y * 2.0);
    let point = far.eye[0].world_from_clip * vec4(ndc, depth, 1.0);
    let seen = display.eye[in.eye].clip_from_world * vec4(point.xyz / point.w, 1.0);
    return CompositeOutput(color, clamp(seen.z / seen.w, 0.0, 1.0));
}
