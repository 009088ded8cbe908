//! Passes drawn without vertex buffers (their vertex stage makes its own positions):
//! the far layer's and the foveated composites, the compositor's depth resolve and the
//! visibility mask. Their WGSL sources and the one pipeline shape they share.

use super::bindings::{declarations, pipeline_layout};
use super::{
    CONTEXTS, DEPTH_RESOLVE_BINDINGS, FAR_COMPOSITE_BINDINGS, FOVEATED_COMPOSITE_BINDINGS,
    KEEP_LIST_BINDINGS, KEEP_TILES_BINDINGS, VISIBILITY_MASK_BINDINGS, Windows, constants,
};

/// The far layer's composite into a stereo display (`wgsl/far_composite.wgsl`).
pub fn far_composite_source() -> String {
    let body = include_str!("../../wgsl/far_composite.wgsl");
    let bindings = declarations(&FAR_COMPOSITE_BINDINGS, 0, &Windows::WHOLE);
    [&constants(), CONTEXTS, &bindings, EYE_HALVES, body].concat()
}

const EYE_HALVES: &str = include_str!("../../wgsl/shared/eye_halves.wgsl");

/// A foveated display's views composited per eye (`crate::foveated_composite`).
pub fn foveated_composite_source() -> String {
    let body = include_str!("../../wgsl/foveated_composite.wgsl");
    let bindings = declarations(&FOVEATED_COMPOSITE_BINDINGS, 0, &Windows::WHOLE);
    [EYE_HALVES, &bindings, body].concat()
}

/// The most hidden triangles a view's visibility mask may have: the mask pass's buffer
/// holds this many per view (`crate::rig::VisibilityMask`).
pub const MAX_MASK_TRIANGLES: usize = 16;

/// The lens's hidden area written to depth (`wgsl/visibility_mask.wgsl`): one view per
/// instance side by side, or per `view_index` in `multiview`.
pub fn visibility_mask_source(multiview: bool) -> String {
    let per_view = 3 * MAX_MASK_TRIANGLES;
    let header = format!(
        "const MASK_VERTICES: u32 = {per_view}u;\nstruct MaskVertices {{ vertices: array<vec4<f32>, {}>, }}\n",
        super::MAX_HIDDEN_VIEWS * per_view
    );
    let bindings = declarations(&VISIBILITY_MASK_BINDINGS, 0, &Windows::WHOLE);
    let body = include_str!("../../wgsl/visibility_mask.wgsl");
    let body = match multiview {
        true => body
            .replace(
                "// MULTIVIEW_VIEW_INDEX",
                "    @builtin(view_index) view: u32,",
            )
            .replace("VIEW *", "view *"),
        false => body.replace("VIEW *", "instance *"),
    };
    [header, bindings, body].concat()
}

/// A kept frame's changed tiles cleared (`wgsl/keep_tiles.wgsl`) in a target of
/// `format`, to the value a pass's clear to `clear` stores there.
pub fn keep_tiles_source(format: wgpu::TextureFormat, clear: wgpu::Color) -> String {
    let [r, g, b, a] = stored_clear(format, clear);
    let clear = format!("const CLEAR_COLOR: vec4<f32> = vec4<f32>({r:?}, {g:?}, {b:?}, {a:?});\n");
    let tile = format!("const TILE: u32 = {}u;\n", super::TILE);
    let bindings = declarations(&KEEP_TILES_BINDINGS, 0, &Windows::WHOLE);
    let body = include_str!("../../wgsl/keep_tiles.wgsl");
    [&clear, &tile, TILE_WORDS, &bindings, body].concat()
}

/// A kept frame's changed tiles listed for the tile pass (`wgsl/keep_list.wgsl`).
pub fn keep_list_source() -> String {
    let constants = format!(
        "const TILE: u32 = {}u;\nconst LIST_GROUP: u32 = {}u;\n",
        super::TILE,
        super::LIST_GROUP
    );
    let bindings = declarations(&KEEP_LIST_BINDINGS, 0, &Windows::WHOLE);
    let body = include_str!("../../wgsl/keep_list.wgsl");
    [&constants, TILE_WORDS, &bindings, body].concat()
}

const TILE_WORDS: &str = include_str!("../../wgsl/shared/tile_words.wgsl");

/// Clear color `c` as a fragment must write it to store what a clear stores: in
/// an 8-bit target, the stored level's own value, which any encoding rounds back to that
/// level (the clear color itself lies between levels, and a clear and a fragment may
/// round it by different code: llvmpipe's differ by a level in sRGB).
fn stored_clear(format: wgpu::TextureFormat, c: wgpu::Color) -> [f32; 4] {
    let linear = [c.r, c.g, c.b, c.a];
    let level = |v: f64| (v.clamp(0.0, 1.0) * 255.0).round() / 255.0;
    let srgb = |v: f64| match v <= 0.0031308 {
        true => 12.92 * v,
        false => 1.055 * v.powf(1.0 / 2.4) - 0.055,
    };
    let linear_of = |s: f64| match s <= 0.04045 {
        true => s / 12.92,
        false => ((s + 0.055) / 1.055).powf(2.4),
    };
    use wgpu::TextureFormat::*;
    let stored = |i: usize, v: f64| match format {
        // Alpha is stored linearly in sRGB formats.
        Rgba8UnormSrgb | Bgra8UnormSrgb if i < 3 => linear_of(level(srgb(v))),
        Rgba8UnormSrgb | Bgra8UnormSrgb | Rgba8Unorm | Bgra8Unorm => level(v),
        _ => v,
    };
    std::array::from_fn(|i| stored(i, linear[i]) as f32)
}

/// The compositor's depth resolve (`wgsl/depth_resolve.wgsl`).
pub fn depth_resolve_source() -> String {
    let body = include_str!("../../wgsl/depth_resolve.wgsl");
    let bindings = declarations(&DEPTH_RESOLVE_BINDINGS, 0, &Windows::WHOLE);
    [&bindings, body].concat()
}

/// What a pass without vertex buffers draws into: its one color target (or none),
/// depth, samples per pixel and, in multiview, its layers.
pub(crate) struct ScreenTargets {
    pub color: Vec<wgpu::ColorTargetState>,
    pub depth: Option<wgpu::DepthStencilState>,
    pub samples: u32,
    pub multiview_mask: Option<std::num::NonZeroU32>,
}

/// Depth written whatever is there (`Always`): a pass that lays depth down.
pub(crate) fn depth_write(format: wgpu::TextureFormat) -> wgpu::DepthStencilState {
    wgpu::DepthStencilState {
        format,
        depth_write_enabled: Some(true),
        depth_compare: Some(wgpu::CompareFunction::Always),
        stencil: Default::default(),
        bias: Default::default(),
    }
}

/// A render pipeline of WGSL `source`'s `vs_main` (which makes its own positions: no
/// vertex buffers) and `fs_main`, its one bind group laid out as `group`.
pub(crate) fn screen_pipeline(
    device: &wgpu::Device,
    label: &str,
    (source, group): (String, &wgpu::BindGroupLayout),
    targets: ScreenTargets,
) -> wgpu::RenderPipeline {
    let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
        label: Some(label),
        source: wgpu::ShaderSource::Wgsl(source.into()),
    });
    let layout = pipeline_layout(device, label, group);
    let color: Vec<_> = targets.color.into_iter().map(Some).collect();
    device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
        label: Some(label),
        layout: Some(&layout),
        vertex: wgpu::VertexState {
            module: &module,
            entry_point: Some("vs_main"),
            compilation_options: Default::default(),
            buffers: &[],
        },
        primitive: wgpu::PrimitiveState::default(),
        depth_stencil: targets.depth,
        multisample: wgpu::MultisampleState {
            count: targets.samples,
            ..Default::default()
        },
        fragment: Some(wgpu::FragmentState {
            module: &module,
            entry_point: Some("fs_main"),
            compilation_options: Default::default(),
            targets: &color,
        }),
        multiview_mask: targets.multiview_mask,
        cache: None,
    })
}
