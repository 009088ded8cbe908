//! What an XR compositor takes from a frame beside its color: each view's depth, as
//! OpenXR's depth layer (`XR_KHR_composition_layer_depth`, an
//! `XrCompositionLayerDepthInfoKHR` chained to each projection view) takes it, so that
//! the runtime can reproject with it.
//!
//! The contract ([`DepthLayer`]): depth runs from 0 at each view's near plane to 1 at
//! its far plane (wgpu's clip space, and OpenXR's `minDepth` 0 and `maxDepth` 1, `nearZ`
//! and `farZ` the view's planes): not reversed. Each view's depth lies where its color
//! does, its rectangle of the display's target, or its layer in multiview. Under MSAA
//! the depth attachment is multisampled, which no runtime takes: [`DepthResolve`]
//! resolves it to each pixel's nearest sample. Without MSAA the attachment itself is
//! the layer.
//!
//! What the depth holds: the near scene as the display drew it. A far layer's instances
//! are composited behind it in color only, so their pixels read the far plane (1).

use serde::Serialize;

use crate::error::Result;
use crate::readback::read_depth;
use crate::rig::{ResolvedDisplay, ViewLayout};
use crate::shaders::{ScreenTargets, depth_write, screen_pipeline};

/// Depth at each view's near plane: OpenXR's `minDepth`.
pub const MIN_DEPTH: f32 = 0.0;
/// Depth at each view's far plane (and where nothing was drawn): OpenXR's `maxDepth`.
pub const MAX_DEPTH: f32 = 1.0;

/// The depth attachment's format, and the resolved layer's.
pub const DEPTH_FORMAT: wgpu::TextureFormat = crate::draw::DEPTH_FORMAT;

/// One view's depth in its display's target.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct DepthView {
    /// Pixels of the target: x, y, width, height (OpenXR's `subImage.imageRect`).
    pub rect: [u32; 4],
    /// The array layer (multiview: the view's index; OpenXR's
    /// `subImage.imageArrayIndex`), else 0.
    pub layer: u32,
    /// The view's near plane in meters (`nearZ`), where depth is [`MIN_DEPTH`].
    pub near: f32,
    /// The view's far plane in meters (`farZ`), where depth is [`MAX_DEPTH`].
    pub far: f32,
}

/// A display's depth as a compositor's depth layer takes it.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct DepthLayer {
    /// [`MIN_DEPTH`].
    pub min_depth: f32,
    /// [`MAX_DEPTH`].
    pub max_depth: f32,
    /// False: depth grows with distance (1 at the far plane).
    pub reversed_z: bool,
    /// How a multisampled attachment became the layer: `"nearest sample"`, or `"none"`
    /// (single-sampled: the attachment itself).
    pub resolve: &'static str,
    /// In the display's view order (left, right; a foveated display's insets after).
    pub views: Vec<DepthView>,
}

impl DepthLayer {
    /// The layer of a display resolved as `display`, its views placed by `layout` (one
    /// layer each when `layered`), drawn with `samples` per pixel.
    pub fn new(
        display: &ResolvedDisplay,
        layout: &ViewLayout,
        layered: bool,
        samples: u32,
    ) -> DepthLayer {
        let views = (display.eyes.iter().zip(layout.viewports()).enumerate())
            .map(|(i, (eye, &[x, y, w, h]))| DepthView {
                rect: match layered {
                    true => [0, 0, w, h],
                    false => [x, y, w, h],
                },
                layer: if layered { i as u32 } else { 0 },
                near: eye.near,
                far: eye.far,
            })
            .collect();
        DepthLayer {
            min_depth: MIN_DEPTH,
            max_depth: MAX_DEPTH,
            reversed_z: false,
            resolve: if samples > 1 {
                "nearest sample"
            } else {
                "none"
            },
            views,
        }
    }
}

/// A display target's depth as its compositor layer takes it, read back (resolved to
/// the nearest sample first when `depth` is multisampled): the width of the whole (the
/// layers side by side) and the values, rows from the top
/// ([`crate::readback::read_depth`]).
pub fn read_layer(
    device: &wgpu::Device,
    queue: &wgpu::Queue,
    depth: &wgpu::Texture,
) -> Result<(u32, Vec<f32>)> {
    if depth.sample_count() == 1 {
        return read_depth(device, queue, depth);
    }
    let output = DepthResolve::create_output(device, depth);
    let mut encoder = device.create_command_encoder(&Default::default());
    DepthResolve::new(device).encode(device, &mut encoder, depth, &output);
    queue.submit([encoder.finish()]);
    read_depth(device, queue, &output)
}

/// Resolves a multisampled depth attachment to each pixel's nearest sample
/// (`wgsl/depth_resolve.wgsl`), layer by layer.
pub struct DepthResolve {
    pipeline: wgpu::RenderPipeline,
    layout: wgpu::BindGroupLayout,
}

impl DepthResolve {
    /// Its pipeline, for any sample count (the shader asks the texture).
    pub fn new(device: &wgpu::Device) -> DepthResolve {
        let label = "stereocull.depth_resolve";
        let list = &crate::shaders::DEPTH_RESOLVE_BINDINGS;
        let windows = &crate::shaders::Windows::WHOLE;
        let layout = crate::shaders::bind_group_layout(device, label, list, windows);
        let source = crate::shaders::depth_resolve_source();
        let targets = ScreenTargets {
            color: Vec::new(),
            depth: Some(depth_write(DEPTH_FORMAT)),
            samples: 1,
            multiview_mask: None,
        };
        let pipeline = screen_pipeline(device, label, (source, &layout), targets);
        DepthResolve { pipeline, layout }
    }

    /// A single-sampled depth texture shaped as `depth` (size and layers) to resolve
    /// into: a render attachment that can be copied out and sampled.
    pub fn create_output(device: &wgpu::Device, depth: &wgpu::Texture) -> wgpu::Texture {
        device.create_texture(&wgpu::TextureDescriptor {
            label: Some("stereocull.compositor_depth"),
            size: depth.size(),
            mip_level_count: 1,
            sample_count: 1,
            dimension: wgpu::TextureDimension::D2,
            format: DEPTH_FORMAT,
            usage: wgpu::TextureUsages::RENDER_ATTACHMENT
                | wgpu::TextureUsages::COPY_SRC
                | wgpu::TextureUsages::TEXTURE_BINDING,
            view_formats: &[],
        })
    }

    /// Records the resolve of every layer of `depth` (multisampled) into `output`
    /// (from [`DepthResolve::create_output`]).
    pub fn encode(
        &self,
        device: &wgpu::Device,
        encoder: &mut wgpu::CommandEncoder,
        depth: &wgpu::Texture,
        output: &wgpu::Texture,
    ) {
        for layer in 0..depth.depth_or_array_layers() {
            let view = |t: &wgpu::Texture| {
                t.create_view(&wgpu::TextureViewDescriptor {
                    dimension: Some(wgpu::TextureViewDimension::D2),
                    base_array_layer: layer,
                    array_layer_count: Some(1),
                    ..Default::default()
                })
            };
            let source = view(depth);
            let bind_group = device.create_bind_group(&wgpu::BindGroupDescriptor {
                label: Some("stereocull.depth_resolve"),
                layout: &self.layout,
                entries: &[wgpu::BindGroupEntry {
                    binding: 0,
                    resource: wgpu::BindingResource::TextureView(&source),
                }],
            });
            let target = view(output);
            let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
                label: Some("stereocull.depth_resolve"),
                color_attachments: &[],
                depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
                    view: &target,
                    depth_ops: Some(wgpu::Operations {
                        load: wgpu::LoadOp::Clear(MAX_DEPTH),
                        store: wgpu::StoreOp::Store,
                    }),
                    stencil_ops: None,
                }),
                ..Default::default()
            });
            pass.set_pipeline(&self.pipeline);
            pass.set_bind_group(0, &bind_group, &[]);
            pass.draw(0..3, 0..1);
        }
    }
}
