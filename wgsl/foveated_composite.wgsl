// A foveated display's four views composited into one image per eye, as XR runtimes
// present them: each eye's outer view stretched over the eye's whole window, its inset
// laid over the part of the window it covers, faded in over a soft border. Drawn as one
// triangle per eye into a double-wide target (src/foveated_composite.rs; its CPU twin is
// composite_cpu there, which this file's arithmetic mirrors step for step).
//
// Texels are read with textureLoad and filtered here rather than by a sampler, so that
// the CPU twin can repeat the filter exactly and no filter reaches across a viewport's
// edge into the neighbouring view.

struct CompositeEye {
    // Source pixels of this eye's outer view and of its inset: x, y, width, height.
    outer_viewport: vec4<f32>,
    inset_viewport: vec4<f32>,
    // Their windows as tangents: left, right, up, down.
    outer_window: vec4<f32>,
    inset_window: vec4<f32>,
    // The inset view's axes from the outer view's (the identity when both look the
    // same way, as a head-fixed rig's do).
    inset_from_outer: mat3x3<f32>,
}

struct CompositeParams {
    eye: array<CompositeEye, 2>,
    // Output pixels per eye.
    eye_size: vec2<f32>,
    // The inset's soft border: the fade's width as a fraction of the inset's size.
    border: f32,
}

// Bindings: FOVEATED_COMPOSITE_BINDINGS in src/shaders/bindings.rs.

// The vertex stage: wgsl/shared/eye_halves.wgsl.

// Bilinear at `at` (source pixels, centers at i + 0.5), clamped to the centers of
// `viewport`'s outermost texels.
fn bilinear(viewport: vec4<f32>, at: vec2<f32>) -> vec4<f32> {
    let p = clamp(at, viewport.xy + 0.5, viewport.xy + viewport.zw - 0.5) - 0.5;
    let base = floor(p);
    let f = p - base;
    let last = vec2<i32>(viewport.xy + viewport.zw) - 1;
    let i0 = vec2<i32>(base);
    let i1 = min(i0 + 1, last);
    let top = mix(textureLoad(source, i0, 0), textureLoad(source, vec2(i1.x, i0.y), 0), f.x);
    let bottom = mix(textureLoad(source, vec2(i0.x, i1.y), 0), textureLoad(source, i1, 0), f.x);
    return mix(top, bottom, f.y);
}

fn smooth_edge(t: f32) -> f32 {
    let x = clamp(t, 0.0, 1.0);
    return x * x * (3.0 - 2.0 * x);
}

@fragment
fn fs_main(in: EyeHalf) -> @location(0) vec4<f32> {
    let e = params.eye[in.eye];
    let uv = (in.position.xy - vec2(f32(in.eye) * params.eye_size.x, 0.0)) / params.eye_size;
    let outer = bilinear(e.outer_viewport, e.outer_viewport.xy + uv * e.outer_viewport.zw);
    let w = e.outer_window;
    let direction = vec3(-w.x + uv.x * (w.x + w.y), w.z - uv.y * (w.z + w.w), -1.0);
    let d = e.inset_from_outer * direction;
    if (d.z >= 0.0) {
        return outer;
    }
    let t = d.xy / -d.z;
    let i = e.inset_window;
    let inset_uv = vec2((t.x + i.x) / (i.x + i.y), (i.z - t.y) / (i.z + i.w));
    let inside = min(min(inset_uv.x, 1.0 - inset_uv.x), min(inset_uv.y, 1.0 - inset_uv.y));
    if (inside <= 0.0) {
        return outer;
    }
    let inset = bilinear(e.inset_viewport, e.inset_viewport.xy + inset_uv * e.inset_viewport.zw);
    return mix(outer, inset, smooth_edge(inside / params.border));
}
