//! Drawing: the pipelines of each material bin (`wgsl/draw*.wgsl`; their state in
//! `pipelines.rs`), the scene on the GPU (`scene.rs`), and the GPU-driven path's
//! multi-draw per bin; render passes in `passes.rs`. The renderer decides what to draw
//! (`renderer::indirect`, `renderer::classic`); this module knows how.

pub mod mask;
mod passes;
mod pipelines;
mod scene;

use std::collections::{BTreeMap, HashMap};

pub use passes::{Attachments, CLEAR_COLOR, begin_pass, cleared_depth, set_viewport};
pub use pipelines::{DEPTH_FORMAT, TargetFormat, VERTEX_ATTRIBUTES, VERTEX_BUFFER};
use pipelines::{pipeline, shadow_pipeline};
pub use scene::{DrawScene, Previous};

use crate::bins::{Bin, BinKind, BinRange};
use crate::cull::targets::{COUNTS_BIN_OFFSET, CullTargets};
use crate::materials;
use crate::records::DrawArgs;
use crate::scene::Shading;
use crate::shaders::Bound;
use crate::shaders::{
    DRAW_BINDINGS, DrawKey, MOTION_BINDINGS, SHADOW_MAP_BINDINGS, Shaders, Windows, bind_group,
    bind_group_layout, shadow_cutout_source, shadow_source,
};

/// What a view's draw draws with: the pipelines and the scene on the GPU.
#[derive(Clone, Copy)]
pub struct Drawing<'a> {
    /// The pipelines and their layouts.
    pub drawer: &'a Drawer,
    /// The geometry, instance records, materials and shadow map.
    pub scene: &'a DrawScene,
}

/// How the draw call is issued, from the device's features.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct DrawFeatures {
    /// `multi_draw_indexed_indirect_count`, else a fixed count over zeroed tails.
    pub indirect_count: bool,
    /// Hardware clip distances keep each eye in its half, else a fragment discard.
    pub clip_distances: bool,
}

impl DrawFeatures {
    /// What `device` has.
    pub fn of(device: &wgpu::Device) -> DrawFeatures {
        let f = device.features();
        DrawFeatures {
            indirect_count: f.contains(wgpu::Features::MULTI_DRAW_INDIRECT_COUNT),
            clip_distances: f.contains(wgpu::Features::CLIP_DISTANCES),
        }
    }
}

/// Draw pipelines by variant, for one color format, and the shadow pass's.
pub struct Drawer {
    layout: wgpu::BindGroupLayout,
    materials_layout: wgpu::BindGroupLayout,
    pipelines: HashMap<DrawKey, wgpu::RenderPipeline>,
    /// With shadows: the depth-only pipeline and the shadow map's size.
    pub shadow: Option<ShadowPipeline>,
    /// How the instance records are bound.
    pub windows: Windows,
    /// How draws are issued on this device.
    pub features: DrawFeatures,
    /// Samples per pixel of the target (cutouts use alpha to coverage above 1).
    samples: u32,
    /// With motion vectors (every built-in pipeline writes motion), or two frames per
    /// submission (the first frame's views read the first pose): group 3's layout, the
    /// earlier records ([`DrawScene::previous`]).
    earlier: Option<wgpu::BindGroupLayout>,
    /// Which of the two reads group 3.
    target: TargetFormat,
}

/// The frame's shadow pass pipelines (`wgsl/shadow.wgsl`, `wgsl/shadow_cutout.wgsl`).
pub struct ShadowPipeline {
    /// The depth-only pipeline, for opaque bins.
    pub pipeline: wgpu::RenderPipeline,
    /// For cutout bins (when the scene has any): discards under the cutoff.
    pub cutout: Option<wgpu::RenderPipeline>,
    /// The shadow map's texels a side.
    pub size: u32,
}

impl Drawer {
    /// Group 0's layout ([`crate::shaders::DRAW_BINDINGS`]).
    pub fn layout(&self) -> &wgpu::BindGroupLayout {
        &self.layout
    }

    /// Builds the pipelines for the given variants, one per bin of `kinds` (the
    /// scene's), rendering into `target`, shaded by each bin's function of `shaders`
    /// (see [`DrawKey::source_with`]), and with
    /// `shadow_size` the shadow pass's, into a map of that many texels a side.
    pub fn new(
        device: &wgpu::Device,
        target: TargetFormat,
        (keys, kinds): (&[DrawKey], &[Bin]),
        shaders: Shaders,
        shadow_size: Option<u32>,
        windows: Windows,
    ) -> Drawer {
        let layout = bind_group_layout(device, "stereocull.draw", &DRAW_BINDINGS, &windows);
        let materials_layout = materials::bind_group_layout(device);
        let shadow_layout = bind_group_layout(
            device,
            "stereocull.shadow_map",
            &SHADOW_MAP_BINDINGS,
            &windows,
        );
        let grouped = target.motion || target.first_pose;
        let earlier = grouped
            .then(|| bind_group_layout(device, "stereocull.motion", &MOTION_BINDINGS, &windows));
        let pipeline_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("stereocull.draw"),
            bind_group_layouts: &[
                Some(&layout),
                Some(&materials_layout),
                Some(&shadow_layout),
                earlier.as_ref(),
            ][..3 + usize::from(grouped)],
            immediate_size: 0,
        });
        let built_in = kinds
            .iter()
            .filter(|k| !matches!(k.shading, Shading::Own(_)));
        let pipelines = (keys.iter())
            .flat_map(|&key| {
                built_in
                    .clone()
                    .map(move |&k| Drawer::variant(key.with_bin(k, target.samples), target))
            })
            .map(|key| {
                let source = key.source_with(shaders.function(key.shading), &windows);
                (
                    key,
                    pipeline(device, &pipeline_layout, key, &source, target),
                )
            })
            .collect();
        let shadow = shadow_size.map(|size| ShadowPipeline {
            pipeline: shadow_pipeline(
                device,
                &[Some(&layout)],
                ("stereocull.shadow", shadow_source(&windows)),
            ),
            cutout: kinds.iter().any(|k| k.alpha == BinKind::Mask).then(|| {
                shadow_pipeline(
                    device,
                    &[Some(&layout), Some(&materials_layout)],
                    ("stereocull.shadow.cutout", shadow_cutout_source(&windows)),
                )
            }),
            size,
        });
        Drawer {
            layout,
            materials_layout,
            pipelines,
            shadow,
            windows,
            features: DrawFeatures::of(device),
            samples: target.samples,
            earlier,
            target,
        }
    }

    /// `key` as drawn into `target`: with motion vectors, or the first pose.
    fn variant(key: DrawKey, target: TargetFormat) -> DrawKey {
        (key.with_motion(target.motion)).with_first_pose(target.first_pose && !target.motion)
    }

    /// The variant for `views` views per instance on this device.
    pub fn key(&self, views: u32) -> DrawKey {
        DrawKey::new(views, self.features.clip_distances)
    }

    /// Binds the frame and a display context, the instances and a visible list.
    pub fn bind_group(
        &self,
        device: &wgpu::Device,
        [frame_context, display_context]: [&wgpu::Buffer; 2],
        scene: &DrawScene,
        visible: wgpu::BufferBinding,
    ) -> wgpu::BindGroup {
        // In DRAW_BINDINGS order.
        let buffers = [
            frame_context.bound(),
            display_context.bound(),
            visible,
            scene.instances.bound(),
        ];
        let (label, layout) = ("stereocull.draw", &self.layout);
        bind_group(
            device,
            label,
            layout,
            &DRAW_BINDINGS,
            &self.windows,
            buffers,
        )
    }

    /// Sets the geometry and the bindings of the built-in pipelines on `pass`: group
    /// 0, the materials (group 1), the shadow map (group 2) and, with motion vectors,
    /// the previous frame (group 3 and the second vertex buffer).
    pub fn bind(pass: &mut wgpu::RenderPass, scene: &DrawScene, bind_group: &wgpu::BindGroup) {
        Drawer::bind_resources(pass, scene, bind_group);
        Drawer::bind_built_in(pass, scene);
        if let Some(previous) = &scene.previous {
            let vertices = previous.vertices.as_ref().unwrap_or(&scene.vertices);
            pass.set_vertex_buffer(1, vertices.slice(..));
        }
    }

    /// The groups of the built-in pipelines from 1 on.
    fn bind_built_in(pass: &mut wgpu::RenderPass, scene: &DrawScene) {
        pass.set_bind_group(1, &scene.materials.bind_group, &[]);
        pass.set_bind_group(2, &scene.shadow_group, &[]);
        if let Some(previous) = &scene.previous {
            pass.set_bind_group(3, &previous.bind_group, &[]);
        }
    }

    /// The geometry and group 0 on `pass`, for whatever pipeline it has (an engine's
    /// own keeps its groups from 1 on).
    pub fn bind_resources(
        pass: &mut wgpu::RenderPass,
        scene: &DrawScene,
        bind_group: &wgpu::BindGroup,
    ) {
        pass.set_bind_group(0, bind_group, &[]);
        pass.set_vertex_buffer(0, scene.vertices.slice(..));
        pass.set_index_buffer(scene.indices.slice(..), wgpu::IndexFormat::Uint32);
    }

    /// What `with` draws bins of `kind` with: `None` skips the bin (blended bins cast
    /// no shadow; a pipeline of the caller's own that is not set).
    pub fn bin_pipeline<'a>(&'a self, with: BinPipelines<'a>, kind: Bin) -> Option<BinDraw<'a>> {
        match (with, kind.shading) {
            (BinPipelines::Draw(_, own), Shading::Own(i)) => own.get(&i).map(BinDraw::Own),
            (BinPipelines::Draw(key, _), _) => {
                let variant = Drawer::variant(key.with_bin(kind, self.samples), self.target);
                Some(BinDraw::BuiltIn(&self.pipelines[&variant]))
            }
            (BinPipelines::Own, _) => Some(BinDraw::Keep),
            (BinPipelines::Shadow, _) => {
                let shadow = self.shadow.as_ref()?;
                match kind.alpha {
                    BinKind::Opaque => Some(BinDraw::BuiltIn(&shadow.pipeline)),
                    BinKind::Mask => shadow.cutout.as_ref().map(BinDraw::BuiltIn),
                    BinKind::Blend => None,
                }
            }
        }
    }

    /// The GPU-driven path's draws: per material bin, its pipeline (of `with`) and one
    /// multi-draw over the bin's range. A pipeline of the caller's own binds its groups
    /// from 1 on, so the built-in bins after it bind the materials and shadow map again.
    /// Returns the draw calls.
    pub fn draw_bins(
        &self,
        pass: &mut wgpu::RenderPass,
        (bins, scene): (&[BinRange], &DrawScene),
        with: BinPipelines,
        cull: &CullTargets,
    ) -> u32 {
        let mut calls = 0;
        let mut groups_taken = false;
        for (b, range) in bins.iter().enumerate() {
            match self.bin_pipeline(with, range.kind) {
                None => continue,
                Some(BinDraw::Keep) => {}
                Some(BinDraw::BuiltIn(pipeline)) => {
                    pass.set_pipeline(pipeline);
                    if std::mem::take(&mut groups_taken) {
                        Drawer::bind_built_in(pass, scene);
                    }
                }
                Some(BinDraw::Own(own)) => {
                    pass.set_pipeline(&own.pipeline);
                    for (g, group) in own.bind_groups.iter().enumerate() {
                        pass.set_bind_group(g as u32 + 1, group, &[]);
                    }
                    groups_taken = true;
                }
            }
            let offset = cull.draws_at + range.first as u64 * size_of::<DrawArgs>() as u64;
            if self.features.indirect_count {
                let count_offset = cull.counts_at + COUNTS_BIN_OFFSET + 4 * b as u64;
                pass.multi_draw_indexed_indirect_count(
                    &cull.draws,
                    offset,
                    &cull.counts,
                    count_offset,
                    range.capacity,
                );
            } else {
                pass.multi_draw_indexed_indirect(&cull.draws, offset, range.capacity);
            }
            calls += 1;
        }
        calls
    }
}

/// A render pipeline of the caller's own for the material bins of
/// [`Shading::Own`]: its layout starts with group 0 (`Renderer::bind_group_layout`), its
/// shader with `Renderer::decode_source(views)`; its own bind groups are set from group
/// 1 on before its bin's multi-draw. It renders into the display's target as the
/// built-in pipelines do (formats, samples, multiview mask) and keeps each eye in its
/// own half (see `Renderer::draw_display_with_own_pipeline`).
#[derive(Clone, Debug)]
pub struct OwnPipeline {
    /// The pipeline.
    pub pipeline: wgpu::RenderPipeline,
    /// Its groups from 1 on, in order.
    pub bind_groups: Vec<wgpu::BindGroup>,
}

/// One display's pipelines of the caller's own, by [`Shading::Own`] index.
pub type OwnPipelines = BTreeMap<u32, OwnPipeline>;

/// No pipelines of the caller's own (the modes and layers that have none).
pub const NO_OWN_PIPELINES: &OwnPipelines = &BTreeMap::new();

/// How one bin is drawn.
pub enum BinDraw<'a> {
    /// With the pipeline the pass already has.
    Keep,
    /// With one of ours, on the built-in groups.
    BuiltIn(&'a wgpu::RenderPipeline),
    /// With the caller's, on its own groups.
    Own(&'a OwnPipeline),
}

/// Which pipelines a view's material bins are drawn with.
#[derive(Clone, Copy, Debug)]
pub enum BinPipelines<'a> {
    /// The built-in draw pipelines of this variant, each bin its own, and the display's
    /// pipelines of the caller's own for [`Shading::Own`] bins.
    Draw(DrawKey, &'a OwnPipelines),
    /// The frame's shadow pass: depth only, cutouts discarding, blended bins skipped.
    Shadow,
    /// The pipeline the pass already has (an engine's own), for every bin.
    Own,
}
