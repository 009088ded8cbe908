//! The GPU-driven path (`instanced` and `multiview`): per display, culling into a
//! visible list and per-mesh draws (three compute dispatches, or the CPU culler and an
//! upload), then one render pass with one multi-draw-indirect call.
//!
//! Per frame on the GPU-culled path the CPU writes one display context per display and
//! records a fixed number of commands: its cost does not depend on the instance count.

use std::time::Instant;

use super::far_pass::{Far, FarLayers};
use super::passes::{PassRecord, Timing, close, compute_pass, draw_pass, open_display};
use super::shadow_pass::{LightCull, ShadowPass};
use super::{
    CullMode, CullState, FrameStats, RendererOptions, TargetViews, context_buffer,
    display_contexts, write,
};
use crate::cull::cpu;
use crate::cull::cpu::FrameCull;
use crate::cull::gpu::{CullScene, CullTargets, GpuCuller};
use crate::draw::{DrawFeatures, DrawScene, Drawer};
use crate::error::Result;
use crate::modes::StereoMode;
use crate::profiling::GpuTimer;
use crate::records::{CullLayout, uniform_bytes};
use crate::rig::{ResolvedRig, Rig};
use crate::scene::Scene;
use crate::shaders::DrawKey;
use crate::shadow::LightView;

/// Where the visible lists and draws come from.
pub(super) enum Culling {
    /// Three compute dispatches per display over scene data uploaded once (after three
    /// per frame for the coarse cull, whose group 1 is `coarse`).
    Gpu {
        culler: GpuCuller,
        scene: Box<CullScene>,
        coarse: Option<wgpu::BindGroup>,
    },
    /// The CPU culler over its own copy of the cull layout; results are uploaded.
    Cpu { layout: CullLayout },
}

/// One display's buffers and bindings.
pub(super) struct IndirectDisplay {
    context: wgpu::Buffer,
    /// Filled by the cull passes or by the CPU upload; read by the draw.
    pub(super) cull: CullTargets,
    /// GPU culling only.
    cull_bind_group: Option<wgpu::BindGroup>,
    draw_bind_group: wgpu::BindGroup,
    /// The pipeline variant, which also fixes the instances per visible object.
    key: DrawKey,
}

pub(super) struct IndirectPath {
    pub(super) culling: Culling,
    drawer: Drawer,
    pub(super) draw_scene: DrawScene,
    /// Draw entries per display: meshes times levels of detail.
    pub(super) max_draws: u32,
    pub(super) displays: Vec<IndirectDisplay>,
    /// With shadows: the frame's shadow pass.
    shadow: Option<ShadowPass>,
    /// With the far layer: the stereo displays' far layers.
    pub(super) far: Option<Far>,
}

impl IndirectPath {
    pub(super) fn new(
        device: &wgpu::Device,
        (scene, layout): (&Scene, CullLayout),
        (rig, frame): (&Rig, &wgpu::Buffer),
        (options, slots): (&RendererOptions, u32),
    ) -> Result<IndirectPath> {
        let multiview = options.mode == StereoMode::Multiview;
        let coarse = options.coarse_for(rig, Some(device));
        let windows = options.windows(device, slots);
        let culling = match options.cull {
            CullMode::Gpu => {
                let culler = GpuCuller::new(device, coarse, windows);
                let coarse_slots = if coarse { rig.displays.len() as u32 } else { 0 };
                let shape = (slots, options.lod_levels(), coarse_slots);
                let scene = Box::new(CullScene::new(device, &layout, shape));
                let coarse = culler.coarse_bind_group(device, &scene);
                Culling::Gpu {
                    culler,
                    scene,
                    coarse,
                }
            }
            CullMode::Cpu => Culling::Cpu { layout },
        };
        let clip = DrawFeatures::of(device).clip_distances;
        let keys: Vec<DrawKey> = rig
            .displays
            .iter()
            .map(|d| match (d.stereo, multiview) {
                (true, true) => DrawKey::MULTIVIEW,
                (true, false) => DrawKey::new(2, clip),
                (false, _) => DrawKey::new(1, clip),
            })
            .collect();
        let drawer = Drawer::new(
            device,
            options.target_format(),
            (&keys, options.material.as_deref()),
            (options.shadow_size(), windows),
        );
        let draw_scene = DrawScene::new(device, &drawer, scene, slots)?;
        let draws = scene.meshes.len() as u32 * options.lod_levels();
        let displays: Vec<IndirectDisplay> = keys
            .iter()
            .map(|&key| {
                let context = context_buffer(device);
                let cull = CullTargets::new(device, slots, draws);
                let cull_bind_group = match &culling {
                    Culling::Gpu { culler, scene, .. } => {
                        Some(culler.bind_group(device, scene, [frame, &context], &cull))
                    }
                    Culling::Cpu { .. } => None,
                };
                IndirectDisplay {
                    draw_bind_group: drawer.bind_group(
                        device,
                        [frame, &context],
                        &draw_scene,
                        &cull.visible,
                    ),
                    context,
                    cull,
                    cull_bind_group,
                    key,
                }
            })
            .collect();
        let shadow = options.shadows.then(|| {
            let culler = match &culling {
                Culling::Gpu { culler, scene, .. } => Some((culler, &**scene)),
                Culling::Cpu { .. } => None,
            };
            ShadowPass::new(
                device,
                (&drawer, &draw_scene),
                frame,
                culler,
                (slots, draws),
            )
        });
        let far = match options.far_layer {
            false => None,
            true => Some(far_layers(
                device,
                (rig, frame, options),
                &culling,
                (&draw_scene, &displays, windows),
                (slots, draws),
            )?),
        };
        Ok(IndirectPath {
            culling,
            drawer,
            draw_scene,
            max_draws: draws,
            displays,
            shadow,
            far,
        })
    }

    /// What edits change: the instance records and the culling state.
    pub(super) fn edit_targets(&mut self) -> (&wgpu::Buffer, CullState<'_>) {
        let culling = match &mut self.culling {
            Culling::Gpu { scene, .. } => CullState::Gpu(scene),
            Culling::Cpu { layout } => CullState::Cpu(layout),
        };
        (&self.draw_scene.instances, culling)
    }

    /// Writes each display's context and, culling on the CPU, its cull results.
    pub(super) fn prepare(
        &mut self,
        queue: &wgpu::Queue,
        rig: &Rig,
        (resolved, frame, light): (&ResolvedRig, &FrameCull, Option<&LightView>),
    ) -> FrameStats {
        let mut contexts = display_contexts(rig, resolved, |i| {
            self.displays[i].key.instances_per_object()
        });
        if let Some(far) = &mut self.far {
            far.plan(rig, resolved, &mut contexts);
        }
        let mut stats = FrameStats::default();
        let start = Instant::now();
        let culls = match &self.culling {
            Culling::Gpu { scene, .. } => {
                let planes: Vec<_> = resolved.displays.iter().map(|d| d.planes).collect();
                stats.bytes_uploaded += scene.write_block_tests(queue, &planes);
                Vec::new()
            }
            Culling::Cpu { layout } => {
                let mut jobs: Vec<_> = self
                    .displays
                    .iter()
                    .zip(&resolved.displays)
                    .map(|(state, r)| r.cull_job(state.key.instances_per_object()))
                    .collect();
                if let Some(far) = &self.far {
                    far.split_jobs(&mut jobs);
                }
                cpu::cull_frame(layout, &jobs, frame)
            }
        };
        stats.cpu_cull = start.elapsed();
        let start = Instant::now();
        for (state, ctx) in self.displays.iter().zip(&contexts) {
            stats.bytes_uploaded += write(queue, &state.context, &uniform_bytes(ctx));
        }
        for (state, out) in self.displays.iter().zip(&culls) {
            stats.bytes_uploaded += state.cull.upload(queue, out);
        }
        if let Some(far) = &self.far {
            let outputs = culls.get(self.displays.len()..).unwrap_or(&[]);
            stats.bytes_uploaded += far.prepare(queue, outputs);
        }
        if let (Some(shadow), Some(light)) = (&self.shadow, light) {
            let cull = match &self.culling {
                Culling::Gpu { culler, scene, .. } => LightCull::Gpu(culler, scene),
                Culling::Cpu { layout } => LightCull::Cpu(layout),
            };
            let size = self.draw_scene.shadow_map.size;
            stats.bytes_uploaded += shadow.prepare(queue, (light, size), &cull, &frame.lod);
        }
        stats.cpu_upload = start.elapsed();
        stats
    }

    /// The frame level's passes: the coarse cull (when it runs, on the GPU), timed as
    /// `coarse_cull` inside a `frame` scope, then the shadow pass (with shadows).
    pub(super) fn encode_frame(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        (timer, log): (&mut Option<&mut GpuTimer>, &mut Vec<PassRecord>),
    ) -> FrameStats {
        let mut stats = FrameStats {
            dispatches: self.encode_coarse(encoder, timer, log),
            ..Default::default()
        };
        if let Some(shadow) = &self.shadow {
            let cull = match &self.culling {
                Culling::Gpu { culler, scene, .. } => LightCull::Gpu(culler, scene),
                Culling::Cpu { layout } => LightCull::Cpu(layout),
            };
            let drawing = (&self.drawer, &self.draw_scene);
            let (dispatches, draw_calls) = shadow.encode(encoder, drawing, &cull, (timer, log));
            stats.dispatches += dispatches;
            stats.draw_calls += draw_calls;
        }
        stats
    }

    fn encode_coarse(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        timer: &mut Option<&mut GpuTimer>,
        log: &mut Vec<PassRecord>,
    ) -> u32 {
        let (
            Culling::Gpu {
                culler,
                scene,
                coarse: Some(args),
            },
            Some(first),
        ) = (&self.culling, self.displays.first())
        else {
            return 0;
        };
        let Some(display) = &first.cull_bind_group else {
            return 0;
        };
        let frame = open_display(timer, "frame", encoder);
        let mut dispatches = 0;
        let what = (log, PassRecord::frame("coarse_cull"));
        compute_pass(encoder, (timer, &frame), what, |pass| {
            dispatches = culler.encode_frame(pass, scene, [display, args]);
        });
        close(timer, encoder, frame);
        dispatches
    }

    /// Display `index`: its cull dispatches (GPU culling), then one pass with one draw
    /// call, timed inside `display`.
    pub(super) fn encode_display(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        (index, target): (usize, &TargetViews),
        (timer, display): Timing,
        log: &mut Vec<PassRecord>,
    ) -> FrameStats {
        let culled = self.encode_cull(encoder, index, (timer, display), log);
        let multiview = self.displays[index].key.multiview;
        let what = (log, PassRecord::display("draw", index));
        let draw_calls = draw_pass(
            encoder,
            target,
            (true, multiview),
            (timer, display),
            what,
            |pass| self.draw(pass, index),
        );
        FrameStats {
            draw_calls: culled.draw_calls + draw_calls,
            ..culled
        }
    }

    /// Display `index`'s cull dispatches (none when culling on the CPU: `prepare`
    /// uploaded the results) and, with a far layer, its far cull and far layer pass,
    /// timed inside `display`.
    pub(super) fn encode_cull(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        index: usize,
        (timer, display): Timing,
        log: &mut Vec<PassRecord>,
    ) -> FrameStats {
        let state = &self.displays[index];
        let gpu = match &self.culling {
            Culling::Gpu {
                culler,
                scene,
                coarse,
            } => Some((culler, &**scene, coarse.is_some().then_some(index as u32))),
            Culling::Cpu { .. } => None,
        };
        let mut stats = FrameStats::default();
        if let (Some((culler, scene, slot)), Some(bind_group)) = (gpu, &state.cull_bind_group) {
            let what = (&mut *log, PassRecord::display("cull", index));
            compute_pass(encoder, (timer, display), what, |pass| {
                culler.encode(pass, scene, bind_group, slot);
            });
            stats.dispatches = GpuCuller::DISPATCHES_PER_DISPLAY;
        }
        if let Some((far, Some(layer))) = self.far.as_ref().map(|f| (f, &f.displays[index])) {
            let at = (index, layer, &self.draw_scene);
            let (dispatches, draw_calls) =
                far.layers.encode(encoder, at, gpu, (timer, display, log));
            stats.dispatches += dispatches;
            stats.draw_calls += draw_calls;
        }
        stats
    }

    /// Display `index`'s one multi-draw-indirect call into `pass`, whose pipeline the
    /// caller set (built on [`Drawer::layout`] and the decode).
    pub(super) fn draw_with_own_pipeline(&self, pass: &mut wgpu::RenderPass, index: usize) {
        let state = &self.displays[index];
        Drawer::bind_resources(pass, &self.draw_scene, &state.draw_bind_group);
        self.drawer.draw_indirect(pass, self.max_draws, &state.cull);
    }

    /// How the instance records are bound.
    pub(super) fn windows(&self) -> crate::shaders::Windows {
        self.drawer.windows
    }

    pub(super) fn bind_group_layout(&self) -> &wgpu::BindGroupLayout {
        self.drawer.layout()
    }

    pub(super) fn cull_targets(&self, index: usize) -> &CullTargets {
        &self.displays[index].cull
    }

    /// Display `index`'s one multi-draw-indirect call into `pass`.
    /// With a far layer, its composite goes first (one more draw call).
    pub(super) fn draw(&self, pass: &mut wgpu::RenderPass, index: usize) -> u32 {
        let state = &self.displays[index];
        let composite = match self.far.as_ref().map(|f| (f, &f.displays[index])) {
            Some((far, Some(layer))) => far.layers.composite(pass, layer),
            _ => 0,
        };
        self.drawer
            .bind(pass, state.key, &self.draw_scene, &state.draw_bind_group);
        self.drawer.draw_indirect(pass, self.max_draws, &state.cull);
        composite + 1
    }
}

/// The far layers of the stereo displays, composited into `displays`' passes.
fn far_layers(
    device: &wgpu::Device,
    (rig, frame, options): (&Rig, &wgpu::Buffer, &RendererOptions),
    culling: &Culling,
    (draw_scene, displays, windows): (&DrawScene, &[IndirectDisplay], crate::shaders::Windows),
    sizes: (u32, u32),
) -> Result<Far> {
    let material = options.material.as_deref();
    let layers = FarLayers::new(
        device,
        (options.target_format(), material),
        (options.far_threshold_px, windows),
    );
    let culler = match culling {
        Culling::Gpu { culler, scene, .. } => Some((culler, &**scene)),
        Culling::Cpu { .. } => None,
    };
    let contexts: Vec<&wgpu::Buffer> = displays.iter().map(|d| &d.context).collect();
    Far::new(
        device,
        (layers, rig),
        (draw_scene, frame, &contexts),
        culler,
        sizes,
    )
}
