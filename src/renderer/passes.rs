//! Recording passes with their timer scopes: a scope per display, a scope per pass
//! inside it, and pipeline statistics around each draw pass, shared by both paths.

use wgpu_profiler::GpuProfilerQuery;

use super::TargetViews;
use crate::draw::begin_pass;
use crate::profiling::GpuTimer;

/// Records one draw pass into `target`, clearing it or not: a `draw` timer scope inside
/// `display`'s and pipeline statistics around what `record` draws (it returns its
/// draw calls).
pub(super) fn draw_pass(
    encoder: &mut wgpu::CommandEncoder,
    target: &TargetViews,
    clear: bool,
    multiview: bool,
    timer: &mut Option<&mut GpuTimer>,
    display: &Option<GpuProfilerQuery>,
    record: impl FnOnce(&mut wgpu::RenderPass) -> u32,
) -> u32 {
    let scope = open_pass(timer, "draw", display, encoder);
    let writes = scope
        .as_ref()
        .and_then(|q| q.render_pass_timestamp_writes());
    let mut pass = begin_pass(encoder, target.attachments(), clear, multiview, writes);
    let counting = timer
        .as_deref_mut()
        .is_some_and(|t| t.begin_statistics(&mut pass));
    let calls = record(&mut pass);
    GpuTimer::end_statistics(&mut pass, counting);
    drop(pass);
    close(timer, encoder, scope);
    calls
}

/// Opens display `name`'s timer scope, when timing.
pub(super) fn open_display(
    timer: &Option<&mut GpuTimer>,
    name: &str,
    encoder: &mut wgpu::CommandEncoder,
) -> Option<GpuProfilerQuery> {
    timer.as_deref().map(|t| t.scope(name, encoder))
}

/// Opens a pass scope inside a display's, when timing; its timestamp writes go into
/// the pass descriptor.
pub(super) fn open_pass(
    timer: &Option<&mut GpuTimer>,
    label: &str,
    display: &Option<GpuProfilerQuery>,
    encoder: &mut wgpu::CommandEncoder,
) -> Option<GpuProfilerQuery> {
    match (timer.as_deref(), display) {
        (Some(t), Some(parent)) => Some(t.pass(label, parent, encoder)),
        _ => None,
    }
}

pub(super) fn close(
    timer: &Option<&mut GpuTimer>,
    encoder: &mut wgpu::CommandEncoder,
    scope: Option<GpuProfilerQuery>,
) {
    if let (Some(t), Some(scope)) = (timer.as_deref(), scope) {
        t.end(encoder, scope);
    }
}
