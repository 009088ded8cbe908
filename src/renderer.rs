//! The embedding API: a [`Renderer`] takes the caller's device, queue and encoder,
//! renders into the caller's texture views (or targets it makes for them), and owns no
//! window and no global state.
//!
//! ```no_run
//! # fn demo(device: &wgpu::Device, queue: &wgpu::Queue) -> stereocull::Result<()> {
//! use stereocull::renderer::{Renderer, RendererOptions};
//! use stereocull::{rig::Rig, scene::Scene};
//!
//! let scene = Scene::load("procedural:10000")?;
//! let mut rig = Rig::preset("hmd")?;
//! let mut renderer = Renderer::new(device, &scene, &rig, RendererOptions::default())?;
//! let targets = renderer.create_targets(device); // or views of your own textures
//! // Each frame: move the viewer, write the contexts, record, submit.
//! rig.viewer.yaw_deg += 1.0;
//! renderer.prepare(queue, &rig)?;
//! let mut encoder = device.create_command_encoder(&Default::default());
//! let views: Vec<_> = targets.iter().map(|t| t.views()).collect();
//! renderer.encode(&mut encoder, &views)?;
//! queue.submit([encoder.finish()]);
//! # Ok(()) }
//! ```
//!
//! Per frame, the GPU-culled path writes one display context per display and records
//! three dispatches and one draw call per display: its CPU cost does not depend on the
//! number of instances. With [`CullMode::Cpu`] the visible lists and draws are computed
//! by [`crate::cull::cpu`] and uploaded instead, into the same buffers.

use std::time::{Duration, Instant};

use crate::contexts::{DisplayContext, uniform_bytes};
use crate::cull::gpu::{COUNT_BYTES, CullScene, CullTargets, GpuCuller};
use crate::cull::{CullOutput, cpu};
use crate::draw::{DEPTH_FORMAT, DrawScene, Drawer};
use crate::error::{Error, Result};
use crate::readback::read_buffer;
use crate::records::{CullLayout, DrawArgs};
use crate::rig::Rig;
use crate::scene::Scene;

/// Where the per-display cull runs.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, clap::ValueEnum, serde::Serialize)]
#[serde(rename_all = "lowercase")]
pub enum CullMode {
    /// Compute passes on the GPU; nothing per instance crosses the bus each frame.
    #[default]
    Gpu,
    /// The rayon culler, then an upload of its results.
    Cpu,
}

#[derive(Clone, Copy, Debug)]
pub struct RendererOptions {
    pub color_format: wgpu::TextureFormat,
    pub cull: CullMode,
}

impl Default for RendererOptions {
    fn default() -> Self {
        RendererOptions {
            color_format: wgpu::TextureFormat::Rgba8UnormSrgb,
            cull: CullMode::Gpu,
        }
    }
}

/// The color and depth views one display renders into: `2W x H` for stereo, `W x H`
/// for mono, where `W x H` is the display's per-eye resolution.
#[derive(Clone, Copy)]
pub struct TargetViews<'a> {
    pub color: &'a wgpu::TextureView,
    pub depth: &'a wgpu::TextureView,
}

/// Textures made by [`Renderer::create_targets`] for callers that have none.
pub struct DisplayTarget {
    pub color: wgpu::Texture,
    pub depth: wgpu::Texture,
    color_view: wgpu::TextureView,
    depth_view: wgpu::TextureView,
}

impl DisplayTarget {
    pub fn views(&self) -> TargetViews<'_> {
        TargetViews {
            color: &self.color_view,
            depth: &self.depth_view,
        }
    }
}

/// What one frame recorded and uploaded.
#[derive(Clone, Copy, Debug, Default, PartialEq, serde::Serialize)]
pub struct FrameStats {
    pub draw_calls: u32,
    pub dispatches: u32,
    pub bytes_uploaded: u64,
    /// CPU time spent culling (zero on the GPU path).
    #[serde(skip)]
    pub cpu_cull: Duration,
}

struct DisplayState {
    views: u32,
    target_size: (u32, u32),
    context: wgpu::Buffer,
    cull: CullTargets,
    cull_bind_group: wgpu::BindGroup,
    draw_bind_group: wgpu::BindGroup,
}

pub struct Renderer {
    cull_mode: CullMode,
    color_format: wgpu::TextureFormat,
    culler: GpuCuller,
    drawer: Drawer,
    cull_scene: CullScene,
    draw_scene: DrawScene,
    /// Kept for CPU culling; the GPU holds its own copy.
    layout: CullLayout,
    displays: Vec<DisplayState>,
}

impl Renderer {
    /// Uploads the scene once and builds the pipelines and per-display buffers.
    pub fn new(
        device: &wgpu::Device,
        scene: &Scene,
        rig: &Rig,
        options: RendererOptions,
    ) -> Result<Renderer> {
        check_device(device, scene)?;
        let scope = device.push_error_scope(wgpu::ErrorFilter::Validation);
        let layout = CullLayout::new(scene);
        let cull_scene = CullScene::new(device, &layout);
        let draw_scene = DrawScene::new(device, scene);
        let culler = GpuCuller::new(device);
        let mut views: Vec<u32> = rig.displays.iter().map(|d| d.views()).collect();
        views.sort_unstable();
        views.dedup();
        let drawer = Drawer::new(device, options.color_format, &views);
        let displays = rig
            .displays
            .iter()
            .map(|d| {
                let context = device.create_buffer(&wgpu::BufferDescriptor {
                    label: Some("stereocull.display_context"),
                    size: <DisplayContext as encase::ShaderType>::min_size().get(),
                    usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
                    mapped_at_creation: false,
                });
                let cull =
                    CullTargets::new(device, cull_scene.instance_count, cull_scene.mesh_count);
                Ok(DisplayState {
                    views: d.views(),
                    target_size: (d.resolution[0] * d.views(), d.resolution[1]),
                    cull_bind_group: culler.bind_group(device, &cull_scene, &context, &cull),
                    draw_bind_group: drawer.bind_group(device, &context, &draw_scene, &cull),
                    context,
                    cull,
                })
            })
            .collect::<Result<Vec<_>>>()?;
        if let Some(e) = pollster::block_on(scope.pop()) {
            return Err(Error::Wgpu(e));
        }
        Ok(Renderer {
            cull_mode: options.cull,
            color_format: options.color_format,
            culler,
            drawer,
            cull_scene,
            draw_scene,
            layout,
            displays,
        })
    }

    pub fn cull_mode(&self) -> CullMode {
        self.cull_mode
    }

    /// Switches between GPU and CPU culling; both write the same buffers.
    pub fn set_cull_mode(&mut self, mode: CullMode) {
        self.cull_mode = mode;
    }

    /// Size of each display's target in pixels (double-wide for stereo).
    pub fn target_sizes(&self) -> Vec<(u32, u32)> {
        self.displays.iter().map(|d| d.target_size).collect()
    }

    /// GPU bytes per instance: the 64-byte instance record, the cull layout and scratch,
    /// and 4 bytes of visible list per display.
    pub fn gpu_bytes_per_instance(&self) -> u64 {
        DrawScene::BYTES_PER_INSTANCE
            + CullScene::BYTES_PER_INSTANCE
            + 4 * self.displays.len() as u64
    }

    /// Writes this frame's display contexts (and, culling on the CPU, the cull results).
    /// `rig` must have the displays the renderer was made with; only poses may change.
    pub fn prepare(&self, queue: &wgpu::Queue, rig: &Rig) -> Result<FrameStats> {
        if rig.displays.len() != self.displays.len()
            || rig
                .displays
                .iter()
                .zip(&self.displays)
                .any(|(d, s)| d.views() != s.views)
        {
            return Err(Error::rig(
                "prepare",
                "the rig's displays differ from the renderer's",
            ));
        }
        let mut stats = FrameStats::default();
        for (i, state) in self.displays.iter().enumerate() {
            let ctx = DisplayContext::new(rig, i)?;
            let bytes = uniform_bytes(&ctx);
            queue.write_buffer(&state.context, 0, &bytes);
            stats.bytes_uploaded += bytes.len() as u64;
            if self.cull_mode == CullMode::Cpu {
                let start = Instant::now();
                let out = cpu::cull(&self.layout, &ctx.planes, ctx.views);
                stats.cpu_cull += start.elapsed();
                stats.bytes_uploaded += upload_cull(queue, &state.cull, &out);
            }
        }
        Ok(stats)
    }

    /// Records every display: its cull dispatches (GPU culling) and its one render pass
    /// with one multi-draw call, into `targets[i]` for display `i`.
    pub fn encode(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        targets: &[TargetViews],
    ) -> Result<FrameStats> {
        if targets.len() != self.displays.len() {
            return Err(Error::Limits(format!(
                "{} targets for {} displays",
                targets.len(),
                self.displays.len()
            )));
        }
        let mut stats = FrameStats::default();
        for (state, target) in self.displays.iter().zip(targets) {
            if self.cull_mode == CullMode::Gpu {
                let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
                    label: Some("stereocull.cull"),
                    timestamp_writes: None,
                });
                self.culler
                    .encode(&mut pass, &self.cull_scene, &state.cull_bind_group);
                stats.dispatches += GpuCuller::DISPATCHES_PER_DISPLAY;
            }
            self.drawer.encode(
                encoder,
                target,
                state.views,
                &self.draw_scene,
                &state.draw_bind_group,
                &state.cull,
            );
            stats.draw_calls += 1;
        }
        Ok(stats)
    }

    /// Color (`RENDER_ATTACHMENT | COPY_SRC`) and depth textures for every display.
    pub fn create_targets(&self, device: &wgpu::Device) -> Vec<DisplayTarget> {
        self.displays
            .iter()
            .map(|d| {
                let texture = |label, format, usage| {
                    device.create_texture(&wgpu::TextureDescriptor {
                        label: Some(label),
                        size: wgpu::Extent3d {
                            width: d.target_size.0,
                            height: d.target_size.1,
                            depth_or_array_layers: 1,
                        },
                        mip_level_count: 1,
                        sample_count: 1,
                        dimension: wgpu::TextureDimension::D2,
                        format,
                        usage,
                        view_formats: &[],
                    })
                };
                let color = texture(
                    "stereocull.color",
                    self.color_format,
                    wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::COPY_SRC,
                );
                let depth = texture(
                    "stereocull.depth",
                    DEPTH_FORMAT,
                    wgpu::TextureUsages::RENDER_ATTACHMENT,
                );
                DisplayTarget {
                    color_view: color.create_view(&Default::default()),
                    depth_view: depth.create_view(&Default::default()),
                    color,
                    depth,
                }
            })
            .collect()
    }

    /// Reads display `index`'s cull buffers back (after the frame was submitted): the
    /// visible list up to the visible total, all draws, and the draw count.
    pub fn read_cull(
        &self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        index: usize,
    ) -> Result<CullOutput> {
        let cull = &self.displays[index].cull;
        let count: Vec<u32> =
            bytemuck::pod_collect_to_vec(&read_buffer(device, queue, &cull.count, COUNT_BYTES)?);
        let visible_bytes = 4 * count[1] as u64;
        let visible = if count[1] == 0 {
            Vec::new()
        } else {
            bytemuck::pod_collect_to_vec(&read_buffer(device, queue, &cull.visible, visible_bytes)?)
        };
        let draws_bytes = (size_of::<DrawArgs>() as u32 * self.cull_scene.mesh_count) as u64;
        let draws =
            bytemuck::pod_collect_to_vec(&read_buffer(device, queue, &cull.draws, draws_bytes)?);
        Ok(CullOutput {
            visible,
            draws,
            draw_count: count[0],
        })
    }

    /// Visible totals of every display, read back from the count buffers.
    pub fn read_visible_counts(
        &self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
    ) -> Result<Vec<u32>> {
        self.displays
            .iter()
            .map(|d| {
                let count: Vec<u32> = bytemuck::pod_collect_to_vec(&read_buffer(
                    device,
                    queue,
                    &d.cull.count,
                    COUNT_BYTES,
                )?);
                Ok(count[1])
            })
            .collect()
    }
}

/// Writes a CPU cull result where the GPU cull would have; returns the bytes written.
fn upload_cull(queue: &wgpu::Queue, targets: &CullTargets, out: &CullOutput) -> u64 {
    let count = [out.draw_count, out.visible.len() as u32];
    let parts: [(&wgpu::Buffer, &[u8]); 3] = [
        (&targets.visible, bytemuck::cast_slice(&out.visible)),
        (&targets.draws, bytemuck::cast_slice(&out.draws)),
        (&targets.count, bytemuck::cast_slice(&count)),
    ];
    parts
        .iter()
        .filter(|(_, bytes)| !bytes.is_empty())
        .map(|(buffer, bytes)| {
            queue.write_buffer(buffer, 0, bytes);
            bytes.len() as u64
        })
        .sum()
}

/// What the GPU path cannot do without, said before anything is built.
fn check_device(device: &wgpu::Device, scene: &Scene) -> Result<()> {
    if !device
        .features()
        .contains(wgpu::Features::INDIRECT_FIRST_INSTANCE)
    {
        return Err(Error::Limits(
            "the device lacks INDIRECT_FIRST_INSTANCE, which GPU-driven drawing needs for per-mesh offsets".into(),
        ));
    }
    let limits = device.limits();
    let largest = [
        64 * scene.instances.len() as u64,
        24 * scene.vertices.len() as u64,
        4 * scene.indices.len() as u64,
    ];
    let max = limits
        .max_storage_buffer_binding_size
        .min(limits.max_buffer_size);
    if let Some(big) = largest.iter().find(|&&b| b > max) {
        return Err(Error::Limits(format!(
            "the scene needs a {big}-byte buffer but the device allows {max} ({} instances)",
            scene.instances.len()
        )));
    }
    Ok(())
}
