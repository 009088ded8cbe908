//! Display targets: the color and depth views each display renders into, and textures
//! of the right shape for callers that have none.

use crate::draw::{Attachments, TargetFormat};

/// The views one display renders into: `2W x H` for stereo, `W x H` for mono, where
/// `W x H` is the display's per-eye resolution; in multiview a stereo display's views are
/// `W x H` with two array layers (left, right). With MSAA, `color` and `depth` have the
/// renderer's sample count and `resolve` is the single-sampled view that receives the
/// image; without, `resolve` is `None`.
#[derive(Clone, Copy)]
pub struct TargetViews<'a> {
    /// The color attachment (multisampled under MSAA).
    pub color: &'a wgpu::TextureView,
    /// The depth attachment.
    pub depth: &'a wgpu::TextureView,
    /// Under MSAA: the single-sampled view the image is resolved into.
    pub resolve: Option<&'a wgpu::TextureView>,
}

impl<'a> TargetViews<'a> {
    pub(crate) fn attachments(&self) -> Attachments<'a> {
        Attachments {
            color: self.color,
            depth: self.depth,
            resolve: self.resolve,
        }
    }
}

/// Textures made by `Renderer::create_targets` for callers that have none.
pub struct DisplayTarget {
    /// The image: single-sampled, `COPY_SRC` (the resolve target under MSAA).
    pub color: wgpu::Texture,
    /// The depth attachment's texture (multisampled under MSAA).
    pub depth: wgpu::Texture,
    color_view: wgpu::TextureView,
    depth_view: wgpu::TextureView,
    /// The multisampled color attachment, under MSAA.
    multisampled: Option<wgpu::TextureView>,
}

impl DisplayTarget {
    /// The views a frame renders into.
    pub fn views(&self) -> TargetViews<'_> {
        match &self.multisampled {
            Some(samples) => TargetViews {
                color: samples,
                depth: &self.depth_view,
                resolve: Some(&self.color_view),
            },
            None => TargetViews {
                color: &self.color_view,
                depth: &self.depth_view,
                resolve: None,
            },
        }
    }
}

/// The shape of one display's target, fixed when the renderer is made.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct TargetShape {
    /// Pixels per eye.
    pub eye_size: (u32, u32),
    /// 2 for stereo, 1 for mono.
    pub views: u32,
    /// Stereo as two array layers (multiview) instead of two halves side by side.
    pub layered: bool,
}

impl TargetShape {
    fn extent(self) -> wgpu::Extent3d {
        let (w, h) = self.eye_size;
        match self.layered {
            true => wgpu::Extent3d {
                width: w,
                height: h,
                depth_or_array_layers: 2,
            },
            false => wgpu::Extent3d {
                width: w * self.views,
                height: h,
                depth_or_array_layers: 1,
            },
        }
    }

    /// Color (`RENDER_ATTACHMENT | COPY_SRC`) and depth textures of this shape in
    /// `format`, and the multisampled color under MSAA.
    pub fn create(self, device: &wgpu::Device, format: TargetFormat) -> DisplayTarget {
        let texture = |label, format, usage, sample_count| {
            device.create_texture(&wgpu::TextureDescriptor {
                label: Some(label),
                size: self.extent(),
                mip_level_count: 1,
                sample_count,
                dimension: wgpu::TextureDimension::D2,
                format,
                usage,
                view_formats: &[],
            })
        };
        let attachment = wgpu::TextureUsages::RENDER_ATTACHMENT;
        let color = texture(
            "stereocull.color",
            format.color,
            attachment | wgpu::TextureUsages::COPY_SRC,
            1,
        );
        let depth = texture("stereocull.depth", format.depth, attachment, format.samples);
        let multisampled = (format.samples > 1).then(|| {
            texture(
                "stereocull.color_msaa",
                format.color,
                attachment,
                format.samples,
            )
        });
        let dimension = match self.layered {
            true => wgpu::TextureViewDimension::D2Array,
            false => wgpu::TextureViewDimension::D2,
        };
        let view = |t: &wgpu::Texture| {
            t.create_view(&wgpu::TextureViewDescriptor {
                dimension: Some(dimension),
                ..Default::default()
            })
        };
        DisplayTarget {
            color_view: view(&color),
            depth_view: view(&depth),
            multisampled: multisampled.as_ref().map(view),
            color,
            depth,
        }
    }
}
