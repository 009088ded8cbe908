// The chapter's Listing 1.3 frame, display and eye contexts. Mirrored by src/contexts.rs (encase); the test
// `contexts_match_wgsl` compares the two layouts member by member.
// Names read like the math: view_from_world is the chapter's mLocation,
// clip_from_view its mProjection, and each X_from_Y has its Y_from_X beside it. The
// built-in passes read only clip_from_world, world_from_clip, position and the cull's
// fields; the view and clip matrices (and the frame's viewer_direction) are there for
// material hooks (RendererOptions::material), which have `frame` and `display` in
// scope: view-space depth, fog, screen-space effects.

struct EyeContext {
    view_from_world: mat4x4<f32>,
    world_from_view: mat4x4<f32>,
    clip_from_view: mat4x4<f32>,
    view_from_clip: mat4x4<f32>,
    // clip_from_view * view_from_world, composed in f64 on the CPU: what vertices use.
    clip_from_world: mat4x4<f32>,
    // Its inverse (f64 too): how fragments find their world position.
    world_from_clip: mat4x4<f32>,
    // The previous frame's clip_from_world, with motion vectors (wgsl/shared/motion.wgsl);
    // else clip_from_world.
    previous_clip_from_world: mat4x4<f32>,
    // The eyeball: apex of this eye's frustum, used for specular.
    position: vec3<f32>,
    // Seconds this view's frame lies after frame.time: the second frame's views of a
    // two-frame submission (RendererOptions::frames_per_submit); else 0.
    time_ahead: f32,
    // Where this view lies in the display's target: x, y, width, height in pixels.
    viewport: vec4<f32>,
    // The view's clip space placed into its viewport of a shared target (one draw for
    // every view): x' = x * p.x + w * p.y, y' = y * p.z + w * p.w.
    placement: vec4<f32>,
}

struct DisplayContext {
    // The combined display frustum (apex behind the eyes), used for culling.
    view_from_world: mat4x4<f32>,
    world_from_view: mat4x4<f32>,
    clip_from_view: mat4x4<f32>,
    view_from_clip: mat4x4<f32>,
    // Left, right, then (foveated) the left and right insets; fewer views repeat the last.
    eye: array<EyeContext, 4>,
    position: vec3<f32>,
    // Pixels of one eye's view (a foveated display's outer view); a stereo target is
    // 2 * resolution.x wide.
    resolution: vec2<f32>,
    // Display frustum planes (left, right, bottom, top, near, far), inside when
    // dot(n, p) + d >= 0: what the cull pass tests.
    planes: array<vec4<f32>, 6>,
    // Instances drawn per visible object (the cull contract's V): 2 for instanced
    // stereo (instance_index >> 1 the object, & 1 the eye), 4 for instanced foveated
    // stereo (/ 4 the object, % 4 the view), else 1.
    instances_per_object: u32,
    // Which eye eye[0] is: 1 in the classic modes' right-eye contexts (both slots hold
    // that eye), else 0.
    first_eye: u32,
    // The far split (src/far_layer.rs): 0 none, 1 keep near, 2 keep far instances,
    // those entirely beyond split_distance from `position` (the display's apex).
    split_keep: u32,
    split_distance: f32,
    // Which of the frame coarse cull's block lists this cull runs over (its display's
    // index; the far layer's cull shares its display's): read only over candidates.
    cull_slot: u32,
    // The display's views: 1 mono, 2 stereo, 4 foveated stereo (occlusion tests each
    // eye's pyramid, whatever the instances per object).
    views: u32,
    // Pixels a sphere's projected bounds grow by each way in the occlusion test: 1 for
    // rounding, more in a far layer's cull (how far its composite carries a far point).
    occlusion_margin_px: f32,
    // 1 where the cull also drops what the display's hidden area (`hidden` at
    // cull_slot, src/cull/hidden.rs) hides in every masked view, else 0.
    hidden: u32,
}

// Once per frame: the viewer (not any eye) and the time in seconds.
struct FrameContext {
    viewer_position: vec3<f32>,
    time: f32,
    // Where the viewer looks (for material hooks; no built-in pass reads it).
    viewer_direction: vec3<f32>,
    // (pixels per radian / pixels of error allowed)^2: see lod_level in cull_math.wgsl.
    lod_scale: f32,
    // The frame-level coarse cull (src/cull/coarse.rs): the frame frustum's planes,
    // pushed out so that they keep every sphere any display keeps, how much radii grow,
    // and the rounding slack per unit of |center|. See grown_test in cull_coarse.wgsl.
    coarse_planes: array<vec4<f32>, 6>,
    coarse_inflation: f32,
    coarse_slack: f32,
    // The frame's light (src/shadow.rs): world to its shadow map's clip space, where
    // it comes from (unit), and 1 when the shadow map was drawn this frame.
    light_from_world: mat4x4<f32>,
    light_direction: vec3<f32>,
    shadows: u32,
    // The previous frame's time, with motion vectors; else time.
    previous_time: f32,
    // The camera's exposure, the light's scale, and its tone mapper (TONEMAP_* in
    // tonemap.wgsl): src/exposure.rs.
    exposure: f32,
    tonemap: u32,
}
