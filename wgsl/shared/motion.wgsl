// Motion vectors (src/motion.rs): where a vertex was in the previous frame, and the
// motion a fragment writes. Group 3 (MOTION_BINDINGS): the instance records as the
// previous frame drew them.

// The previous clip position, in view `eye`, of the vertex of visible slot `slot`
// whose local position in the previous frame's vertices was `was_local`.
fn previous_clip(was_local: vec3<f32>, slot: u32, eye: u32) -> vec4<f32> {
    let id = visible[slot];
    let now = instances_at(id);
    var was = previous_instances_at(id);
    // A newcomer to its slot has no previous transform of its own: it takes its
    // current one, as if it had stood there.
    if (was.generation != now.generation) {
        was = now;
    }
    let world = animated(was, was_local, frame.previous_time);
    return display.eye[eye].previous_clip_from_world * vec4(world, 1.0);
}

// Current minus previous pixel of the fragment at `frag` (pixels of the target) whose
// previous clip position is `was`, in the view drawn into `viewport`: zero where the
// point was behind the previous eye (no pixel to come from).
fn pixel_motion(frag: vec2<f32>, was: vec4<f32>, viewport: vec4<f32>) -> vec2<f32> {
    if (was.w <= 0.0) {
        return vec2(0.0);
    }
    let ndc = was.xy / was.w;
    return frag - (viewport.xy + vec2(ndc.x * 0.5 + 0.5, 0.5 - ndc.y * 0.5) * viewport.zw);
}
