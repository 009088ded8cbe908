//! The frame level: passes recorded once per frame, whatever the displays and eyes,
//! before any display's cull: posing animations on the GPU (`pose.rs`), morph targets
//! (`morph.rs`), skinning (`skin.rs`) and the light's shadow map (`shadow.rs`, culled
//! like one more view).

use crate::renderer::recorder::Recorder;

pub(super) mod lights;
pub(super) mod morph;
pub(super) mod pose;
pub(super) mod shadow;
pub(super) mod skin;

/// A frame pass of one dispatch, `size` workgroups of `pipeline` over `group`, logged as
/// the frame pass `name`; returns the dispatches.
pub(super) fn one_dispatch(
    encoder: &mut wgpu::CommandEncoder,
    rec: &mut Recorder,
    name: &'static str,
    (pipeline, group, size): (&wgpu::ComputePipeline, &wgpu::BindGroup, (u32, u32)),
) -> u32 {
    let (mut pass, open) = rec.frame_pass(encoder, name);
    pass.set_pipeline(pipeline);
    pass.set_bind_group(0, group, &[]);
    pass.dispatch_workgroups(size.0, size.1, 1);
    rec.close_frame_pass(encoder, pass, open);
    1
}
