//! Render passes of the draw: their attachments, how one opens, the cleared depth
//! attachment, and one view's viewport.

use std::num::NonZeroU32;

/// Dark enough that any lit object stands out in tests.
pub const CLEAR_COLOR: wgpu::Color = wgpu::Color {
    r: 0.02,
    g: 0.02,
    b: 0.03,
    a: 1.0,
};

/// What a draw pass renders into.
#[derive(Clone, Copy)]
pub struct Attachments<'a> {
    /// Where color is drawn (multisampled under MSAA).
    pub color: &'a wgpu::TextureView,
    /// The depth attachment.
    pub depth: &'a wgpu::TextureView,
    /// Where a multisampled `color` is resolved at the end of the pass.
    pub resolve: Option<&'a wgpu::TextureView>,
    /// With motion vectors: the motion attachment and its resolve under MSAA.
    pub motion: Option<(&'a wgpu::TextureView, Option<&'a wgpu::TextureView>)>,
}

/// Opens a render pass on `target`, clearing it or keeping what earlier passes drew
/// (multisampled color is kept too, then resolved again); `multiview_mask` renders
/// those layers of a layered target (multiview; `DrawKey::multiview_mask`).
pub fn begin_pass<'e>(
    encoder: &'e mut wgpu::CommandEncoder,
    target: Attachments,
    clear: bool,
    multiview_mask: Option<NonZeroU32>,
    (timestamp_writes, occlusion_query_set): (
        Option<wgpu::RenderPassTimestampWrites>,
        Option<&wgpu::QuerySet>,
    ),
) -> wgpu::RenderPass<'e> {
    let (color_load, depth_load, motion_load) = if clear {
        let still = wgpu::Color::TRANSPARENT;
        use wgpu::LoadOp::Clear;
        (Clear(CLEAR_COLOR), Clear(1.0), Clear(still))
    } else {
        (wgpu::LoadOp::Load, wgpu::LoadOp::Load, wgpu::LoadOp::Load)
    };
    let attachment = |view, resolve_target, load| {
        Some(wgpu::RenderPassColorAttachment {
            view,
            depth_slice: None,
            resolve_target,
            ops: wgpu::Operations {
                load,
                store: wgpu::StoreOp::Store,
            },
        })
    };
    let color = attachment(target.color, target.resolve, color_load);
    // Pixels no surface covers move by zero.
    let motion = (target.motion).and_then(|(view, resolve)| attachment(view, resolve, motion_load));
    let used = 1 + usize::from(motion.is_some());
    encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
        label: Some("stereocull.draw"),
        color_attachments: &[color, motion][..used],
        depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
            view: target.depth,
            depth_ops: Some(wgpu::Operations {
                load: depth_load,
                store: wgpu::StoreOp::Store,
            }),
            stencil_ops: None,
        }),
        timestamp_writes,
        occlusion_query_set,
        multiview_mask,
    })
}

/// `view` as a depth attachment cleared to the far plane and kept.
pub fn cleared_depth(view: &wgpu::TextureView) -> wgpu::RenderPassDepthStencilAttachment<'_> {
    wgpu::RenderPassDepthStencilAttachment {
        view,
        depth_ops: Some(wgpu::Operations {
            load: wgpu::LoadOp::Clear(1.0),
            store: wgpu::StoreOp::Store,
        }),
        stencil_ops: None,
    }
}

/// Restricts drawing to one view's `[x, y, width, height]` of its display's target (an
/// eye's half of a double-wide target, a foveated display's viewport).
pub fn set_viewport(pass: &mut wgpu::RenderPass, [x, y, w, h]: [u32; 4]) {
    pass.set_viewport(x as f32, y as f32, w as f32, h as f32, 0.0, 1.0);
    pass.set_scissor_rect(x, y, w, h);
}
