//! Display targets: the color and depth views each display renders into, and textures
//! of the right shape for callers that have none.

use super::frames;
use super::options::{RendererOptions, StereoMode};
use crate::draw::{Attachments, TargetFormat};
use crate::motion::MOTION_FORMAT;
use crate::rig::ViewLayout;

/// The views one display renders into: `2W x H` for stereo, `W x H` for mono, where
/// `W x H` is the display's per-eye resolution, and for foveated stereo its four
/// viewports side by side ([`crate::rig::Display::layout`]); in multiview a stereo display's views are
/// `W x H` with two array layers (left, right). With MSAA, `color` and `depth` have the
/// renderer's sample count and `resolve` is the single-sampled view that receives the
/// image; without, `resolve` is `None`. With motion vectors, `motion` is the second
/// color attachment ([`crate::motion::MOTION_FORMAT`], the same size and samples), with
/// its own resolve under MSAA.
#[derive(Clone, Copy)]
pub struct TargetViews<'a> {
    /// The color attachment (multisampled under MSAA).
    pub color: &'a wgpu::TextureView,
    /// The depth attachment.
    pub depth: &'a wgpu::TextureView,
    /// Under MSAA: the single-sampled view the image is resolved into.
    pub resolve: Option<&'a wgpu::TextureView>,
    /// With motion vectors: the motion attachment, and under MSAA the view it is
    /// resolved into.
    pub motion: Option<(&'a wgpu::TextureView, Option<&'a wgpu::TextureView>)>,
}

impl<'a> TargetViews<'a> {
    pub(crate) fn attachments(&self) -> Attachments<'a> {
        Attachments {
            color: self.color,
            depth: self.depth,
            resolve: self.resolve,
            motion: self.motion,
        }
    }
}

/// Textures made by `Renderer::create_targets` for callers that have none.
pub struct DisplayTarget {
    /// The image: single-sampled, `COPY_SRC` and `TEXTURE_BINDING` (the resolve target
    /// under MSAA; a foveated display's composite reads it).
    pub color: wgpu::Texture,
    /// The depth attachment's texture (multisampled under MSAA).
    pub depth: wgpu::Texture,
    color_view: wgpu::TextureView,
    depth_view: wgpu::TextureView,
    /// The multisampled color attachment, under MSAA.
    multisampled: Option<wgpu::TextureView>,
    /// With motion vectors: each pixel's motion (single-sampled, `COPY_SRC`; the
    /// resolve target under MSAA).
    pub motion: Option<wgpu::Texture>,
    /// Its view, and the multisampled attachment's under MSAA.
    motion_views: Option<(wgpu::TextureView, Option<wgpu::TextureView>)>,
}

impl DisplayTarget {
    /// The views a frame renders into.
    pub fn views(&self) -> TargetViews<'_> {
        let motion = self
            .motion_views
            .as_ref()
            .map(|(view, samples)| match samples {
                Some(samples) => (samples, Some(view)),
                None => (view, None),
            });
        match &self.multisampled {
            Some(samples) => TargetViews {
                color: samples,
                depth: &self.depth_view,
                resolve: Some(&self.color_view),
                motion,
            },
            None => TargetViews {
                color: &self.color_view,
                depth: &self.depth_view,
                resolve: None,
                motion,
            },
        }
    }
}

/// The shape of one display's target, fixed when the renderer is made.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct TargetShape {
    /// Where each view lies (pixels per eye, side by side).
    pub layout: ViewLayout,
    /// One array layer per view (multiview), each the size of the largest view, instead
    /// of the views side by side.
    pub layered: bool,
}

impl TargetShape {
    /// The shape of rig display `d`'s target under `options`: one array layer per view
    /// for a stereo display in multiview, else its views side by side (with two frames
    /// per submission, both frames').
    pub fn of(d: &crate::rig::Display, options: &RendererOptions) -> TargetShape {
        let layered = options.mode == StereoMode::Multiview && d.stereo;
        TargetShape {
            layout: frames::layout(d, layered, options.frames_per_submit),
            layered,
        }
    }

    /// Pixels of one eye's view (a foveated display's outer view; in multiview, every
    /// layer's).
    pub fn eye_size(&self) -> (u32, u32) {
        let [_, _, w, h] = self.layout.viewports[0];
        (w, h)
    }

    /// Views: 1 mono, 2 stereo, 4 foveated stereo.
    pub fn views(&self) -> u32 {
        self.layout.views
    }

    fn extent(self) -> wgpu::Extent3d {
        let ((w, h), layers) = match self.layered {
            true => (self.eye_size(), self.views()),
            false => (self.layout.size, 1),
        };
        wgpu::Extent3d {
            width: w,
            height: h,
            depth_or_array_layers: layers,
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
        // TEXTURE_BINDING: a foveated display's composite reads it.
        let color = texture(
            "stereocull.color",
            format.color,
            attachment | wgpu::TextureUsages::COPY_SRC | wgpu::TextureUsages::TEXTURE_BINDING,
            1,
        );
        // TEXTURE_BINDING: occlusion reduces it into pyramids; COPY_SRC: tests read it.
        let depth_usage =
            attachment | wgpu::TextureUsages::TEXTURE_BINDING | wgpu::TextureUsages::COPY_SRC;
        let depth = texture(
            "stereocull.depth",
            format.depth,
            depth_usage,
            format.samples,
        );
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
        // COPY_SRC: read back; TEXTURE_BINDING: a compositor samples it.
        let motion = format.motion.then(|| {
            let usage = wgpu::TextureUsages::COPY_SRC | wgpu::TextureUsages::TEXTURE_BINDING;
            texture("stereocull.motion", MOTION_FORMAT, attachment | usage, 1)
        });
        let motion_views = motion.as_ref().map(|m| {
            let samples = (format.samples > 1).then(|| {
                texture(
                    "stereocull.motion_msaa",
                    MOTION_FORMAT,
                    attachment,
                    format.samples,
                )
            });
            (view(m), samples.as_ref().map(view))
        });
        DisplayTarget {
            color_view: view(&color),
            depth_view: view(&depth),
            multisampled: multisampled.as_ref().map(view),
            color,
            depth,
            motion,
            motion_views,
        }
    }
}
