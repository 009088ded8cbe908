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
//! renderer.encode(&mut encoder, &views, None)?; // or Some(&mut timer) for GPU timings
//! queue.submit([encoder.finish()]);
//! # Ok(()) }
//! ```
//!
//! Per frame, the GPU-culled path writes one display context per display and records
//! three dispatches and one draw call per display: its CPU cost does not depend on the
//! number of instances. With [`CullMode::Cpu`] the visible lists and draws are computed
//! by [`crate::cull::cpu`] and uploaded instead, into the same buffers. The classic
//! stereo modes ([`StereoMode`]) draw the same images the way engines did before.

use std::time::{Duration, Instant};

use crate::contexts::{DisplayContext, uniform_bytes};
use crate::cull::gpu::{COUNT_BYTES, CullScene, CullTargets, GpuCuller};
use crate::cull::{CullOutput, cpu};
use crate::draw::{DEPTH_FORMAT, DrawFeatures, DrawScene, Drawer, begin_pass, set_eye_viewport};
use crate::error::{Error, Result};
pub use crate::modes::StereoMode;
use crate::profiling::GpuTimer;
use crate::readback::read_pod;
use crate::records::{CullLayout, DrawArgs, MeshRecord};
use crate::rig::Rig;
use crate::scene::{Scene, Vertex};
use crate::shaders::DrawKey;

/// Where the per-display cull runs.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash, clap::ValueEnum, serde::Serialize)]
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
    pub mode: StereoMode,
}

impl Default for RendererOptions {
    fn default() -> Self {
        RendererOptions {
            color_format: wgpu::TextureFormat::Rgba8UnormSrgb,
            cull: CullMode::Gpu,
            mode: StereoMode::Instanced,
        }
    }
}

/// The color and depth views one display renders into: `2W x H` for stereo, `W x H`
/// for mono, where `W x H` is the display's per-eye resolution; in [`StereoMode::Multiview`]
/// a stereo display's views are `W x H` with two array layers (left, right).
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

/// What one frame recorded and uploaded, and the CPU time of its phases.
#[derive(Clone, Copy, Debug, Default, PartialEq, serde::Serialize)]
pub struct FrameStats {
    pub draw_calls: u32,
    pub dispatches: u32,
    pub bytes_uploaded: u64,
    /// CPU culling (zero on the GPU path).
    #[serde(skip)]
    pub cpu_cull: Duration,
    /// Writing contexts and cull results into buffers.
    #[serde(skip)]
    pub cpu_upload: Duration,
}

/// One eye of a stereo display in the classic modes: its own context (that eye as
/// `eye[0]`, one view) and, for multi-camera, its own visible list.
struct EyeState {
    context: wgpu::Buffer,
    visible: Option<wgpu::Buffer>,
    bind_group: wgpu::BindGroup,
}

struct DisplayState {
    /// Views of the display (2 stereo, 1 mono).
    views: u32,
    /// Views per instance in the cull contract: 2 only for instanced stereo.
    cull_views: u32,
    eye_size: (u32, u32),
    context: wgpu::Buffer,
    cull: CullTargets,
    cull_bind_group: wgpu::BindGroup,
    draw_bind_group: wgpu::BindGroup,
    eyes: Vec<EyeState>,
}

pub struct Renderer {
    mode: StereoMode,
    cull_mode: CullMode,
    color_format: wgpu::TextureFormat,
    culler: GpuCuller,
    drawer: Drawer,
    cull_scene: CullScene,
    draw_scene: DrawScene,
    /// Kept for CPU culling; the GPU holds its own copy.
    layout: CullLayout,
    displays: Vec<DisplayState>,
    /// The classic modes' CPU culls of this frame: per display, one result, or one per
    /// eye (multi-camera).
    per_instance: Vec<Vec<CullOutput>>,
}

impl Renderer {
    /// Uploads the scene once and builds the pipelines and per-display buffers.
    pub fn new(
        device: &wgpu::Device,
        scene: &Scene,
        rig: &Rig,
        options: RendererOptions,
    ) -> Result<Renderer> {
        check_device(device, scene, options)?;
        let scope = device.push_error_scope(wgpu::ErrorFilter::Validation);
        let layout = CullLayout::new(scene);
        let cull_scene = CullScene::new(device, &layout);
        let draw_scene = DrawScene::new(device, scene);
        let culler = GpuCuller::new(device);
        let drawer = Drawer::new(
            device,
            options.color_format,
            &draw_keys(device, rig, options.mode),
        );
        let new_context = || {
            device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("stereocull.display_context"),
                size: <DisplayContext as encase::ShaderType>::min_size().get(),
                usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
                mapped_at_creation: false,
            })
        };
        let n = cull_scene.instance_count;
        let displays = rig
            .displays
            .iter()
            .map(|d| {
                let context = new_context();
                let cull = CullTargets::new(device, n, cull_scene.mesh_count);
                let per_eye = options.mode.per_instance() && d.stereo;
                let eyes = (0..if per_eye { 2 } else { 0 })
                    .map(|_| {
                        let context = new_context();
                        let visible = (options.mode == StereoMode::MultiCamera)
                            .then(|| CullTargets::new(device, n, 1).visible);
                        let bind_group = drawer.bind_group(
                            device,
                            &context,
                            &draw_scene,
                            visible.as_ref().unwrap_or(&cull.visible),
                        );
                        EyeState {
                            context,
                            visible,
                            bind_group,
                        }
                    })
                    .collect();
                DisplayState {
                    views: d.views(),
                    cull_views: if d.stereo {
                        options.mode.stereo_views()
                    } else {
                        1
                    },
                    eye_size: (d.resolution[0], d.resolution[1]),
                    cull_bind_group: culler.bind_group(device, &cull_scene, &context, &cull),
                    draw_bind_group: drawer.bind_group(
                        device,
                        &context,
                        &draw_scene,
                        &cull.visible,
                    ),
                    context,
                    cull,
                    eyes,
                }
            })
            .collect();
        if let Some(e) = pollster::block_on(scope.pop()) {
            return Err(Error::Wgpu(e));
        }
        Ok(Renderer {
            mode: options.mode,
            cull_mode: options.cull,
            color_format: options.color_format,
            culler,
            drawer,
            cull_scene,
            draw_scene,
            layout,
            displays,
            per_instance: Vec::new(),
        })
    }

    pub fn mode(&self) -> StereoMode {
        self.mode
    }

    pub fn cull_mode(&self) -> CullMode {
        self.cull_mode
    }

    /// GPU bytes per instance: the 64-byte instance record, the cull layout and scratch,
    /// and 4 bytes of visible list per display.
    pub fn gpu_bytes_per_instance(&self) -> u64 {
        DrawScene::BYTES_PER_INSTANCE
            + CullScene::BYTES_PER_INSTANCE
            + 4 * self.displays.len() as u64
    }

    /// Writes this frame's contexts (and, culling on the CPU, the cull results).
    /// `rig` must have the displays the renderer was made with; only poses may change.
    pub fn prepare(&mut self, queue: &wgpu::Queue, rig: &Rig) -> Result<FrameStats> {
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
        let contexts = (0..self.displays.len())
            .map(|i| {
                let mut ctx = DisplayContext::new(rig, i)?;
                ctx.views = self.displays[i].cull_views;
                Ok(ctx)
            })
            .collect::<Result<Vec<_>>>()?;
        let mut stats = FrameStats::default();
        let start = Instant::now();
        let mut culls = self.cpu_culls(rig, &contexts)?.into_iter();
        stats.cpu_cull = start.elapsed();
        let start = Instant::now();
        self.per_instance.clear();
        for (state, ctx) in self.displays.iter().zip(&contexts) {
            let mut writes = vec![(&state.context, uniform_bytes(ctx))];
            for (e, eye) in state.eyes.iter().enumerate() {
                let one_eye = DisplayContext {
                    eye: [ctx.eye[e]; 2],
                    ..*ctx
                };
                writes.push((&eye.context, uniform_bytes(&one_eye)));
            }
            for (buffer, bytes) in writes {
                queue.write_buffer(buffer, 0, &bytes);
                stats.bytes_uploaded += bytes.len() as u64;
            }
            let display_culls = culls.next().unwrap_or_default();
            stats.bytes_uploaded += self.upload_culls(queue, state, &display_culls);
            if self.mode.per_instance() {
                self.per_instance.push(display_culls);
            }
        }
        stats.cpu_upload = start.elapsed();
        Ok(stats)
    }

    /// This frame's CPU culls per display, all in one pass over the spheres: none on
    /// the GPU path, one against each display frustum, or one per eye (multi-camera).
    fn cpu_culls(&self, rig: &Rig, contexts: &[DisplayContext]) -> Result<Vec<Vec<CullOutput>>> {
        if self.cull_mode == CullMode::Gpu {
            return Ok(Vec::new());
        }
        let mut jobs = Vec::new();
        let mut per_display = Vec::new();
        for (i, ctx) in contexts.iter().enumerate() {
            if self.mode == StereoMode::MultiCamera && !self.displays[i].eyes.is_empty() {
                let eyes = rig.eyes(i)?;
                jobs.extend(eyes.iter().map(|e| (e.frustum().planes, 1)));
                per_display.push(eyes.len());
            } else {
                jobs.push((ctx.planes, ctx.views));
                per_display.push(1);
            }
        }
        let mut outputs = cpu::cull_many(&self.layout, &jobs).into_iter();
        Ok(per_display
            .iter()
            .map(|&k| outputs.by_ref().take(k).collect())
            .collect())
    }

    /// Uploads CPU cull results where the draws read them; returns the bytes written.
    fn upload_culls(&self, queue: &wgpu::Queue, state: &DisplayState, culls: &[CullOutput]) -> u64 {
        match (self.mode, culls) {
            (_, []) => 0,
            (StereoMode::MultiCamera, [left, right]) => {
                let visible = |e: usize| {
                    state.eyes[e]
                        .visible
                        .as_ref()
                        .unwrap_or(&state.cull.visible)
                };
                write(queue, visible(0), bytemuck::cast_slice(&left.visible))
                    + write(queue, visible(1), bytemuck::cast_slice(&right.visible))
            }
            (mode, [out, ..]) if mode.per_instance() => write(
                queue,
                &state.cull.visible,
                bytemuck::cast_slice(&out.visible),
            ),
            (_, [out, ..]) => {
                let count = [out.draw_count, out.visible.len() as u32];
                write(
                    queue,
                    &state.cull.visible,
                    bytemuck::cast_slice(&out.visible),
                ) + write(queue, &state.cull.draws, bytemuck::cast_slice(&out.draws))
                    + write(queue, &state.cull.count, bytemuck::cast_slice(&count))
            }
        }
    }

    /// Records every display into `targets[i]` for display `i`: its cull dispatches (GPU
    /// culling) and its passes. With a timer, each pass is timed as `cull` or `draw`.
    pub fn encode(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        targets: &[TargetViews],
        mut timer: Option<&mut GpuTimer>,
    ) -> Result<FrameStats> {
        if targets.len() != self.displays.len() {
            return Err(Error::Limits(format!(
                "{} targets for {} displays",
                targets.len(),
                self.displays.len()
            )));
        }
        let mut stats = FrameStats::default();
        for (i, (state, target)) in self.displays.iter().zip(targets).enumerate() {
            if self.cull_mode == CullMode::Gpu {
                let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
                    label: Some("stereocull.cull"),
                    timestamp_writes: timer.as_deref_mut().and_then(|t| t.compute("cull")),
                });
                self.culler
                    .encode(&mut pass, &self.cull_scene, &state.cull_bind_group);
                stats.dispatches += GpuCuller::DISPATCHES_PER_DISPLAY;
            }
            stats.draw_calls += if self.mode.per_instance() {
                self.encode_per_instance(encoder, target, state, &self.per_instance[i], &mut timer)
            } else {
                self.encode_indirect(encoder, target, state, &mut timer)
            };
        }
        if let Some(t) = timer {
            t.resolve(encoder);
        }
        Ok(stats)
    }

    /// Instanced and multiview: one pass, one multi-draw call.
    fn encode_indirect(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        target: &TargetViews,
        state: &DisplayState,
        timer: &mut Option<&mut GpuTimer>,
    ) -> u32 {
        let multiview = self.mode == StereoMode::Multiview && state.views == 2;
        let key = if multiview {
            DrawKey::MULTIVIEW
        } else {
            self.drawer.key(state.cull_views)
        };
        let writes = timer.as_deref_mut().and_then(|t| t.render("draw"));
        let mut pass = begin_pass(encoder, target, true, multiview, writes);
        let counting = begin_statistics(timer, &mut pass);
        self.drawer
            .bind(&mut pass, key, &self.draw_scene, &state.draw_bind_group);
        self.drawer
            .draw_indirect(&mut pass, self.cull_scene.mesh_count, &state.cull);
        GpuTimer::end_statistics(&mut pass, counting);
        1
    }

    /// The classic modes: a draw call per visible instance and eye.
    fn encode_per_instance(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        target: &TargetViews,
        state: &DisplayState,
        culls: &[CullOutput],
        timer: &mut Option<&mut GpuTimer>,
    ) -> u32 {
        let key = self.drawer.key(1);
        if state.eyes.is_empty() || self.mode == StereoMode::SinglePass {
            let writes = timer.as_deref_mut().and_then(|t| t.render("draw"));
            let mut pass = begin_pass(encoder, target, true, false, writes);
            let counting = begin_statistics(timer, &mut pass);
            let calls = if state.eyes.is_empty() {
                self.drawer
                    .bind(&mut pass, key, &self.draw_scene, &state.draw_bind_group);
                instance_draws(&culls[0])
                    .map(|d| draw(&mut pass, d))
                    .count() as u32
            } else {
                self.drawer
                    .bind(&mut pass, key, &self.draw_scene, &state.eyes[0].bind_group);
                single_pass_cadence(&mut pass, &culls[0], &state.eyes, state.eye_size)
            };
            GpuTimer::end_statistics(&mut pass, counting);
            return calls;
        }
        let mut calls = 0;
        for (e, eye) in state.eyes.iter().enumerate() {
            let writes = timer.as_deref_mut().and_then(|t| t.render("draw"));
            let mut pass = begin_pass(encoder, target, e == 0, false, writes);
            let counting = begin_statistics(timer, &mut pass);
            self.drawer
                .bind(&mut pass, key, &self.draw_scene, &eye.bind_group);
            set_eye_viewport(&mut pass, e as u32, state.eye_size);
            calls += instance_draws(&culls[e.min(culls.len() - 1)])
                .map(|d| draw(&mut pass, d))
                .count() as u32;
            GpuTimer::end_statistics(&mut pass, counting);
        }
        calls
    }

    /// Headless convenience: [`Renderer::prepare`], [`Renderer::encode`] into a new encoder
    /// and submit, rendering into `targets` (from [`Renderer::create_targets`]).
    pub fn submit_frame(
        &mut self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        rig: &Rig,
        targets: &[DisplayTarget],
    ) -> Result<FrameStats> {
        let prepared = self.prepare(queue, rig)?;
        let mut encoder = device.create_command_encoder(&Default::default());
        let views: Vec<_> = targets.iter().map(DisplayTarget::views).collect();
        let recorded = self.encode(&mut encoder, &views, None)?;
        queue.submit([encoder.finish()]);
        Ok(FrameStats {
            bytes_uploaded: prepared.bytes_uploaded,
            cpu_cull: prepared.cpu_cull,
            cpu_upload: prepared.cpu_upload,
            ..recorded
        })
    }

    /// Color (`RENDER_ATTACHMENT | COPY_SRC`) and depth textures for every display, shaped
    /// as [`TargetViews`] describes for this renderer's mode.
    pub fn create_targets(&self, device: &wgpu::Device) -> Vec<DisplayTarget> {
        self.displays
            .iter()
            .map(|d| {
                let layered = self.mode == StereoMode::Multiview && d.views == 2;
                let (w, h) = d.eye_size;
                let size = match layered {
                    true => wgpu::Extent3d {
                        width: w,
                        height: h,
                        depth_or_array_layers: 2,
                    },
                    false => wgpu::Extent3d {
                        width: w * d.views,
                        height: h,
                        depth_or_array_layers: 1,
                    },
                };
                let texture = |label, format, usage| {
                    device.create_texture(&wgpu::TextureDescriptor {
                        label: Some(label),
                        size,
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
                let view = |t: &wgpu::Texture| {
                    t.create_view(&wgpu::TextureViewDescriptor {
                        dimension: Some(if layered {
                            wgpu::TextureViewDimension::D2Array
                        } else {
                            wgpu::TextureViewDimension::D2
                        }),
                        ..Default::default()
                    })
                };
                DisplayTarget {
                    color_view: view(&color),
                    depth_view: view(&depth),
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
        let [draw_count, visible_total] = read_counts(device, queue, cull)?;
        let visible = match visible_total {
            0 => Vec::new(),
            n => read_pod(device, queue, &cull.visible, 4 * n as u64)?,
        };
        let draws_bytes = (size_of::<DrawArgs>() as u32 * self.cull_scene.mesh_count) as u64;
        Ok(CullOutput {
            visible,
            draws: read_pod(device, queue, &cull.draws, draws_bytes)?,
            draw_count,
        })
    }

    /// Visible totals of every display: read back from the count buffers on the
    /// indirect paths, taken from this frame's CPU culls in the classic modes.
    pub fn read_visible_counts(
        &self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
    ) -> Result<Vec<u32>> {
        if self.mode.per_instance() {
            return Ok(self
                .per_instance
                .iter()
                .map(|c| c[0].visible.len() as u32)
                .collect());
        }
        self.displays
            .iter()
            .map(|d| Ok(read_counts(device, queue, &d.cull)?[1]))
            .collect()
    }
}

/// The count buffer: the draw count and the visible total.
fn read_counts(device: &wgpu::Device, queue: &wgpu::Queue, cull: &CullTargets) -> Result<[u32; 2]> {
    let counts: Vec<u32> = read_pod(device, queue, &cull.count, COUNT_BYTES)?;
    Ok([counts[0], counts[1]])
}

fn begin_statistics(timer: &mut Option<&mut GpuTimer>, pass: &mut wgpu::RenderPass) -> bool {
    timer
        .as_deref_mut()
        .is_some_and(|t| t.begin_statistics(pass))
}

fn write(queue: &wgpu::Queue, buffer: &wgpu::Buffer, bytes: &[u8]) -> u64 {
    if !bytes.is_empty() {
        queue.write_buffer(buffer, 0, bytes);
    }
    bytes.len() as u64
}

/// One per-instance draw: index range, base vertex, and the slot in the visible list.
type InstanceDraw = (std::ops::Range<u32>, i32, u32);

/// The per-instance draws of a one-view cull result, in visible-list order.
fn instance_draws(out: &CullOutput) -> impl Iterator<Item = InstanceDraw> + '_ {
    out.draws[..out.draw_count as usize].iter().flat_map(|d| {
        let indices = d.first_index..d.first_index + d.index_count;
        (d.first_instance..d.first_instance + d.instance_count)
            .map(move |slot| (indices.clone(), d.base_vertex, slot))
    })
}

fn draw(pass: &mut wgpu::RenderPass, (indices, base_vertex, slot): InstanceDraw) {
    pass.draw_indexed(indices, base_vertex, slot..slot + 1);
}

/// Single-pass stereo: each instance drawn for both eyes, in the left, right, right, left
/// cadence so that the eye (viewport and binding) switches once per instance, not twice.
fn single_pass_cadence(
    pass: &mut wgpu::RenderPass,
    out: &CullOutput,
    eyes: &[EyeState],
    eye_size: (u32, u32),
) -> u32 {
    let mut current = usize::MAX;
    let mut calls = 0;
    for (k, d) in instance_draws(out).enumerate() {
        let order = if k % 2 == 0 { [0, 1] } else { [1, 0] };
        for e in order {
            if e != current {
                pass.set_bind_group(0, &eyes[e].bind_group, &[]);
                set_eye_viewport(pass, e as u32, eye_size);
                current = e;
            }
            draw(pass, d.clone());
            calls += 1;
        }
    }
    calls
}

/// The draw variants a rig needs in a mode.
fn draw_keys(device: &wgpu::Device, rig: &Rig, mode: StereoMode) -> Vec<DrawKey> {
    let clip = DrawFeatures::of(device).clip_distances;
    let mut keys: Vec<DrawKey> = rig
        .displays
        .iter()
        .map(|d| match (d.stereo, mode) {
            (true, StereoMode::Multiview) => DrawKey::MULTIVIEW,
            (true, StereoMode::Instanced) => DrawKey::new(2, clip),
            _ => DrawKey::new(1, clip),
        })
        .collect();
    keys.sort_by_key(|k| (k.views, k.multiview));
    keys.dedup();
    keys
}

/// What a mode cannot do without, said before anything is built.
fn check_device(device: &wgpu::Device, scene: &Scene, options: RendererOptions) -> Result<()> {
    let features = device.features();
    let mode = options.mode.name();
    if options.mode.per_instance() && options.cull == CullMode::Gpu {
        return Err(Error::Unsupported(format!(
            "{mode} records a draw call per visible instance, so it culls on the CPU: use --cull cpu"
        )));
    }
    if !options.mode.per_instance() && !features.contains(wgpu::Features::INDIRECT_FIRST_INSTANCE) {
        return Err(Error::Unsupported(format!(
            "{mode} needs INDIRECT_FIRST_INSTANCE (per-mesh offsets in indirect draws), which this device lacks"
        )));
    }
    if options.mode == StereoMode::Multiview && !features.contains(wgpu::Features::MULTIVIEW) {
        return Err(Error::Unsupported(
            "multiview is unavailable: the device lacks MULTIVIEW".into(),
        ));
    }
    let limits = device.limits();
    // Storage buffers are bound whole, so the binding limit holds for them; vertex and
    // index buffers are not bindings and only need to fit one buffer.
    let storage = limits
        .max_storage_buffer_binding_size
        .min(limits.max_buffer_size);
    let buffers = [
        (
            "instance records",
            DrawScene::BYTES_PER_INSTANCE,
            scene.instances.len(),
            storage,
        ),
        (
            "mesh records",
            size_of::<MeshRecord>() as u64,
            scene.meshes.len(),
            storage,
        ),
        (
            "vertices",
            size_of::<Vertex>() as u64,
            scene.vertices.len(),
            limits.max_buffer_size,
        ),
        (
            "indices",
            size_of::<u32>() as u64,
            scene.indices.len(),
            limits.max_buffer_size,
        ),
    ];
    for (what, size, count, max) in buffers {
        let bytes = size * count as u64;
        if bytes > max {
            return Err(Error::Limits(format!(
                "the scene's {count} {what} need a {bytes}-byte buffer but the device allows {max}"
            )));
        }
    }
    Ok(())
}
