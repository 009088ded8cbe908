//! The far layers of the indirect path ([`crate::far_layer`]): per stereo display, the
//! far instances' cull (by the frame's culler), one pass drawing them once into the
//! display's far layer, and the composite that opens the display's own pass.

use crate::bins::Bin;
use crate::contexts::DisplayContext;
use crate::draw::{
    BinPipelines, CLEAR_COLOR, DEPTH_FORMAT, DrawScene, Drawer, Drawing, NO_OWN_PIPELINES,
    TargetFormat, cleared_depth,
};
use crate::far_layer::FarPlan;
use crate::occlusion::Phase;
use crate::renderer::culler::Culler;
use crate::renderer::recorder::{PassRecord, Recorder};
use crate::renderer::uploads::Writes;
use crate::renderer::view::ViewPass;
use crate::shaders::{
    DrawKey, FAR_COMPOSITE_BINDINGS, ScreenTargets, Shaders, Windows, bind_group_layout,
    far_composite_source, screen_pipeline,
};

/// What every far layer shares: the mono pipeline drawing into them (single-sampled),
/// the composite pipeline and its layout.
pub struct FarLayers {
    drawer: Drawer,
    composite: wgpu::RenderPipeline,
    composite_layout: wgpu::BindGroupLayout,
    sampler: wgpu::Sampler,
    color: wgpu::TextureFormat,
}

/// One stereo display's far layer: one more view, and its textures.
pub struct FarDisplay {
    /// The display it belongs to (and whose coarse blocks its cull runs over).
    index: usize,
    view: ViewPass,
    color: wgpu::TextureView,
    depth: wgpu::TextureView,
    composite_bind_group: wgpu::BindGroup,
}

impl FarLayers {
    pub(super) fn new(
        device: &wgpu::Device,
        format: TargetFormat,
        kinds: &[Bin],
        shaders: Shaders,
        windows: crate::shaders::Windows,
    ) -> FarLayers {
        let single = TargetFormat {
            depth: DEPTH_FORMAT,
            samples: 1,
            motion: false,
            ..format
        };
        let key = DrawKey::new(1, false);
        let drawer = Drawer::new(device, single, (&[key], kinds), shaders, None, windows);
        let composite_layout = composite_layout(device);
        FarLayers {
            composite: composite_pipeline(device, &composite_layout, format),
            drawer,
            composite_layout,
            sampler: device.create_sampler(&wgpu::SamplerDescriptor {
                label: Some("stereocull.far_sampler"),
                mag_filter: wgpu::FilterMode::Linear,
                min_filter: wgpu::FilterMode::Linear,
                ..Default::default()
            }),
            color: format.color,
        }
    }

    /// Display `index`'s far layer for `plan`, drawn as `view`: its textures and the
    /// composite's bindings (`display` is the display's context, which it reads).
    pub(super) fn display(
        &self,
        device: &wgpu::Device,
        index: usize,
        view: ViewPass,
        display: &wgpu::Buffer,
        plan: &FarPlan,
    ) -> FarDisplay {
        let texture = |label, format| {
            device
                .create_texture(&wgpu::TextureDescriptor {
                    label: Some(label),
                    size: wgpu::Extent3d {
                        width: plan.size.0,
                        height: plan.size.1,
                        depth_or_array_layers: 1,
                    },
                    mip_level_count: 1,
                    sample_count: 1,
                    dimension: wgpu::TextureDimension::D2,
                    format,
                    usage: wgpu::TextureUsages::RENDER_ATTACHMENT
                        | wgpu::TextureUsages::TEXTURE_BINDING,
                    view_formats: &[],
                })
                .create_view(&Default::default())
        };
        let color = texture("stereocull.far_color", self.color);
        let depth = texture("stereocull.far_depth", DEPTH_FORMAT);
        let composite_bind_group = device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("stereocull.far_composite"),
            layout: &self.composite_layout,
            entries: &[
                buffer_entry(0, display),
                buffer_entry(1, view.context()),
                view_entry(2, &color),
                view_entry(3, &depth),
                wgpu::BindGroupEntry {
                    binding: 4,
                    resource: wgpu::BindingResource::Sampler(&self.sampler),
                },
            ],
        });
        FarDisplay {
            index,
            view,
            color,
            depth,
            composite_bind_group,
        }
    }

    /// Records `far`'s cull in `phase` (on the GPU: over its display's blocks with the
    /// coarse cull; [`Phase::Tested`] after its display's pyramids) and its far layer
    /// pass, inside its display's scope. Returns (dispatches, draw calls).
    pub(super) fn encode(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        far: &FarDisplay,
        phase: Phase,
        scene: &DrawScene,
        culler: &Culler,
        rec: &mut Recorder,
    ) -> (u32, u32) {
        let index = far.index;
        let cull = PassRecord::display("far_cull", index);
        let dispatches = (far.view).encode_cull_in(encoder, culler, phase, rec, cull);
        let mut open = rec.open(encoder, PassRecord::display("far_layer", index));
        let mut pass = encoder
            .begin_render_pass(&wgpu::RenderPassDescriptor {
                label: Some("stereocull.far_layer"),
                color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                    view: &far.color,
                    depth_slice: None,
                    resolve_target: None,
                    ops: wgpu::Operations {
                        load: wgpu::LoadOp::Clear(CLEAR_COLOR),
                        store: wgpu::StoreOp::Store,
                    },
                })],
                depth_stencil_attachment: Some(cleared_depth(&far.depth)),
                timestamp_writes: open.render_writes(),
                occlusion_query_set: None,
                multiview_mask: None,
            })
            .forget_lifetime();
        rec.count(&mut pass, &mut open);
        let with = BinPipelines::Draw(DrawKey::new(1, false), NO_OWN_PIPELINES);
        let draw_calls = far.view.draw(&mut pass, self.drawing(scene), with);
        rec.close_render(encoder, pass, open);
        (dispatches, draw_calls)
    }

    pub(super) fn drawing<'a>(&'a self, scene: &'a DrawScene) -> Drawing<'a> {
        Drawing {
            drawer: &self.drawer,
            scene,
        }
    }

    /// The composite into the display's pass, before its near geometry (with occlusion,
    /// before what its late phase draws): one draw, one instance per eye.
    pub(super) fn composite(&self, pass: &mut wgpu::RenderPass, far: &FarDisplay) -> u32 {
        pass.set_pipeline(&self.composite);
        pass.set_bind_group(0, &far.composite_bind_group, &[]);
        pass.draw(0..3, 0..2);
        1
    }
}

impl FarDisplay {
    /// Its cull, as the culler keeps it.
    pub(super) fn cull_pass(&self) -> &crate::renderer::culler::CullPass {
        self.view.cull_pass()
    }

    /// Its cull outputs, per the cull contract.
    pub(super) fn cull(&self) -> &crate::cull::targets::CullTargets {
        self.view.cull()
    }

    /// Writes this frame's far context for `plan` (over the coarse cull's `slot`, its
    /// display's), with occlusion the context its cull tests with (paired with
    /// `display`'s), and the culler's far cull. Returns the bytes written.
    pub(super) fn prepare(
        &self,
        to: Writes,
        plan: &FarPlan,
        display: &DisplayContext,
        culler: &Culler,
    ) -> u64 {
        let slot = self.index as u32;
        self.view.prepare(to, &plan.context(slot), culler)
            + (self.view).prepare_cull_context(to.pose, &plan.tested_context(display))
    }
}

fn buffer_entry(binding: u32, buffer: &wgpu::Buffer) -> wgpu::BindGroupEntry<'_> {
    wgpu::BindGroupEntry {
        binding,
        resource: buffer.as_entire_binding(),
    }
}

fn view_entry(binding: u32, view: &wgpu::TextureView) -> wgpu::BindGroupEntry<'_> {
    wgpu::BindGroupEntry {
        binding,
        resource: wgpu::BindingResource::TextureView(view),
    }
}

/// The composite's layout ([`FAR_COMPOSITE_BINDINGS`]).
fn composite_layout(device: &wgpu::Device) -> wgpu::BindGroupLayout {
    let label = "stereocull.far_composite";
    bind_group_layout(device, label, &FAR_COMPOSITE_BINDINGS, &Windows::WHOLE)
}

/// Writes color and the far points' depth as each eye sees them where nothing drawn
/// before is nearer, at the display's sample count. Opening the pass (on a cleared
/// depth, which every depth passes) it wins where near geometry drawn next ties it;
/// drawn after a display's early phase, it wins those ties too: the same image.
fn composite_pipeline(
    device: &wgpu::Device,
    layout: &wgpu::BindGroupLayout,
    format: TargetFormat,
) -> wgpu::RenderPipeline {
    let label = "stereocull.far_composite";
    let depth = wgpu::DepthStencilState {
        format: format.depth,
        depth_write_enabled: Some(true),
        depth_compare: Some(wgpu::CompareFunction::LessEqual),
        stencil: Default::default(),
        bias: Default::default(),
    };
    let targets = ScreenTargets {
        color: vec![format.color.into()],
        depth: Some(depth),
        samples: format.samples,
        multiview_mask: None,
    };
    screen_pipeline(device, label, (far_composite_source(), layout), targets)
}
