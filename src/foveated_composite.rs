//! A foveated display's four views composited into one image per eye, as XR runtimes
//! present them (for the PNG, and for engines that present themselves): each eye's outer
//! view stretched over the eye's window, its inset laid over the part it covers and
//! faded in over a soft border. [`FoveatedComposite`] draws it on the GPU into a
//! double-wide target; [`composite_cpu`] is its CPU twin.

use encase::ShaderType;
use glam::{DMat3, Mat3, Vec2, Vec4};

use crate::materials::{linear_from_srgb, srgb_from_linear};
use crate::records::uniform_bytes;
use crate::rig::{ResolvedDisplay, ViewLayout};

/// The inset's soft border by default: the fade spans this fraction of the inset's
/// size on each side (runtimes blend over a few percent of the inset).
pub const DEFAULT_BORDER: f32 = 0.08;

/// One eye's part of [`CompositeParams`].
#[derive(Clone, Copy, Debug, PartialEq, ShaderType)]
pub struct CompositeEye {
    /// Source pixels of the eye's outer view: x, y, width, height.
    pub outer_viewport: Vec4,
    /// Source pixels of the eye's inset.
    pub inset_viewport: Vec4,
    /// The outer view's window as tangents: left, right, up, down.
    pub outer_window: Vec4,
    /// The inset's window.
    pub inset_window: Vec4,
    /// The inset view's axes from the outer view's.
    pub inset_from_outer: Mat3,
}

/// What the composite of one foveated display reads (`wgsl/foveated_composite.wgsl`).
#[derive(Clone, Copy, Debug, PartialEq, ShaderType)]
pub struct CompositeParams {
    /// Left, right.
    pub eye: [CompositeEye; 2],
    /// Output pixels per eye.
    pub eye_size: Vec2,
    /// The soft border's width as a fraction of the inset's size.
    pub border: f32,
}

impl CompositeParams {
    /// The composite of `display` (a foveated display's four views, resolved for the
    /// frame that drew them) whose target is laid out as `layout`, into `eye_size`
    /// pixels per eye. `None` unless the display has four views.
    pub fn new(
        display: &ResolvedDisplay,
        layout: &ViewLayout,
        eye_size: [u32; 2],
    ) -> Option<CompositeParams> {
        let [outer_l, outer_r, inset_l, inset_r] = display.eyes.as_slice() else {
            return None;
        };
        let viewport = |i: usize| Vec4::from(layout.viewports[i].map(|v| v as f32));
        let window = |f: &crate::frustum::Fov| Vec4::new(f.left, f.right, f.up, f.down);
        let eye = |e: usize, outer: &crate::frustum::View, inset: &crate::frustum::View| {
            let outer_axes = outer.world_from_view.matrix3;
            let inset_axes: DMat3 = inset.world_from_view.matrix3;
            CompositeEye {
                outer_viewport: viewport(e),
                inset_viewport: viewport(e + 2),
                outer_window: window(&outer.fov),
                inset_window: window(&inset.fov),
                inset_from_outer: (inset_axes.transpose() * outer_axes).as_mat3(),
            }
        };
        Some(CompositeParams {
            eye: [eye(0, outer_l, inset_l), eye(1, outer_r, inset_r)],
            eye_size: Vec2::new(eye_size[0] as f32, eye_size[1] as f32),
            border: DEFAULT_BORDER,
        })
    }

    /// The composite of display `index` of `rig` (its pose as it stands), drawn as
    /// `layout` says (`Renderer::layout`), into the display's resolution per eye; `None`
    /// for a display without four views.
    pub fn of_display(
        rig: &crate::rig::Rig,
        index: usize,
        layout: &ViewLayout,
    ) -> crate::Result<Option<CompositeParams>> {
        let resolved = rig.resolve()?;
        let display = &rig.displays[index];
        Ok(CompositeParams::new(
            &resolved.displays[index],
            layout,
            display.resolution,
        ))
    }

    /// The output's size: both eyes side by side.
    pub fn output_size(&self) -> (u32, u32) {
        (2 * self.eye_size.x as u32, self.eye_size.y as u32)
    }
}

/// The GPU composite: a pipeline for one output format.
pub struct FoveatedComposite {
    pipeline: wgpu::RenderPipeline,
    layout: wgpu::BindGroupLayout,
}

impl FoveatedComposite {
    /// The pipeline writing `format` (the source's format too: sRGB sources are read
    /// and written as linear values, as the sampler-free filter wants).
    pub fn new(device: &wgpu::Device, format: wgpu::TextureFormat) -> FoveatedComposite {
        let label = "stereocull.foveated_composite";
        let layout = bind_group_layout(device);
        let source = crate::shaders::foveated_composite_source();
        let targets = crate::shaders::ScreenTargets {
            color: vec![format.into()],
            depth: None,
            samples: 1,
            multiview_mask: None,
        };
        let pipeline = crate::shaders::screen_pipeline(device, label, (source, &layout), targets);
        FoveatedComposite { pipeline, layout }
    }

    /// Records the composite of `source` (the display's single-sampled color, laid out
    /// as `params` says) into `target` (`params.output_size()`, this pipeline's format):
    /// one pass, one draw of one triangle per eye.
    pub fn encode(
        &self,
        device: &wgpu::Device,
        encoder: &mut wgpu::CommandEncoder,
        source: &wgpu::TextureView,
        params: &CompositeParams,
        target: &wgpu::TextureView,
    ) {
        use wgpu::util::DeviceExt;
        let uniform = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("stereocull.foveated_composite"),
            contents: &uniform_bytes(params),
            usage: wgpu::BufferUsages::UNIFORM,
        });
        let bind_group = device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("stereocull.foveated_composite"),
            layout: &self.layout,
            entries: &[
                wgpu::BindGroupEntry {
                    binding: 0,
                    resource: uniform.as_entire_binding(),
                },
                wgpu::BindGroupEntry {
                    binding: 1,
                    resource: wgpu::BindingResource::TextureView(source),
                },
            ],
        });
        let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
            label: Some("stereocull.foveated_composite"),
            color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                view: target,
                depth_slice: None,
                resolve_target: None,
                ops: wgpu::Operations {
                    load: wgpu::LoadOp::Clear(wgpu::Color::BLACK),
                    store: wgpu::StoreOp::Store,
                },
            })],
            ..Default::default()
        });
        pass.set_pipeline(&self.pipeline);
        pass.set_bind_group(0, &bind_group, &[]);
        pass.draw(0..3, 0..2);
    }
}

impl FoveatedComposite {
    /// A texture of the composite's output size in `format`, to render into and copy
    /// from (`RENDER_ATTACHMENT | COPY_SRC`).
    pub fn create_output(
        device: &wgpu::Device,
        params: &CompositeParams,
        format: wgpu::TextureFormat,
    ) -> wgpu::Texture {
        let (width, height) = params.output_size();
        device.create_texture(&wgpu::TextureDescriptor {
            label: Some("stereocull.foveated_composite"),
            size: wgpu::Extent3d {
                width,
                height,
                depth_or_array_layers: 1,
            },
            mip_level_count: 1,
            sample_count: 1,
            dimension: wgpu::TextureDimension::D2,
            format,
            usage: wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::COPY_SRC,
            view_formats: &[],
        })
    }
}

fn bind_group_layout(device: &wgpu::Device) -> wgpu::BindGroupLayout {
    let list = &crate::shaders::FOVEATED_COMPOSITE_BINDINGS;
    let windows = &crate::shaders::Windows::WHOLE;
    crate::shaders::bind_group_layout(device, "stereocull.foveated_composite", list, windows)
}

/// The CPU twin of the GPU composite, on an sRGB RGBA8 image of the display's target:
/// the same arithmetic in f32 on linear values, step for step.
pub fn composite_cpu(source: &image::RgbaImage, params: &CompositeParams) -> image::RgbaImage {
    let (w, h) = params.output_size();
    let linear: Vec<Vec4> = source.pixels().map(|p| decode(p.0)).collect();
    let texel = |x: i32, y: i32| linear[(y as u32 * source.width() + x as u32) as usize];
    image::RgbaImage::from_fn(w, h, |x, y| {
        let eye = (x >= params.eye_size.x as u32) as usize;
        let center = Vec2::new(x as f32 + 0.5, y as f32 + 0.5);
        encode(composite_pixel(
            &params.eye[eye],
            params,
            eye,
            center,
            &texel,
        ))
    })
}

fn composite_pixel(
    e: &CompositeEye,
    params: &CompositeParams,
    eye: usize,
    position: Vec2,
    texel: &impl Fn(i32, i32) -> Vec4,
) -> Vec4 {
    let uv = (position - Vec2::new(eye as f32 * params.eye_size.x, 0.0)) / params.eye_size;
    let (ov, iv) = (e.outer_viewport, e.inset_viewport);
    let outer = bilinear(
        ov,
        ov.truncate().truncate() + uv * Vec2::new(ov.z, ov.w),
        texel,
    );
    let w = e.outer_window;
    let direction = glam::Vec3::new(-w.x + uv.x * (w.x + w.y), w.z - uv.y * (w.z + w.w), -1.0);
    let d = e.inset_from_outer * direction;
    if d.z >= 0.0 {
        return outer;
    }
    let t = Vec2::new(d.x, d.y) / -d.z;
    let i = e.inset_window;
    let inset_uv = Vec2::new((t.x + i.x) / (i.x + i.y), (i.z - t.y) / (i.z + i.w));
    let inside = (inset_uv.x.min(1.0 - inset_uv.x)).min(inset_uv.y.min(1.0 - inset_uv.y));
    if inside <= 0.0 {
        return outer;
    }
    let at = Vec2::new(iv.x, iv.y) + inset_uv * Vec2::new(iv.z, iv.w);
    let inset = bilinear(iv, at, texel);
    mix(outer, inset, smooth_edge(inside / params.border))
}

fn bilinear(viewport: Vec4, at: Vec2, texel: &impl Fn(i32, i32) -> Vec4) -> Vec4 {
    let origin = Vec2::new(viewport.x, viewport.y);
    let size = Vec2::new(viewport.z, viewport.w);
    let p = at.clamp(origin + 0.5, origin + size - 0.5) - 0.5;
    let base = p.floor();
    let f = p - base;
    let last = (origin + size).as_ivec2() - 1;
    let i0 = base.as_ivec2();
    let i1 = (i0 + 1).min(last);
    let top = mix(texel(i0.x, i0.y), texel(i1.x, i0.y), f.x);
    let bottom = mix(texel(i0.x, i1.y), texel(i1.x, i1.y), f.x);
    mix(top, bottom, f.y)
}

/// WGSL's `mix`: `a * (1 - t) + b * t`.
fn mix(a: Vec4, b: Vec4, t: f32) -> Vec4 {
    a * (1.0 - t) + b * t
}

fn smooth_edge(t: f32) -> f32 {
    let x = t.clamp(0.0, 1.0);
    x * x * (3.0 - 2.0 * x)
}

fn decode(p: [u8; 4]) -> Vec4 {
    let c = |v: u8| linear_from_srgb(v as f32 / 255.0);
    Vec4::new(c(p[0]), c(p[1]), c(p[2]), p[3] as f32 / 255.0)
}

fn encode(v: Vec4) -> image::Rgba<u8> {
    let c = |v: f32| (srgb_from_linear(v.clamp(0.0, 1.0)) * 255.0).round() as u8;
    image::Rgba([
        c(v.x),
        c(v.y),
        c(v.z),
        (v.w.clamp(0.0, 1.0) * 255.0).round() as u8,
    ])
}
