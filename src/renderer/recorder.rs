//! Recording passes with their timer scopes: a scope per display, a scope per pass
//! inside it, and pipeline statistics around each draw pass, shared by both paths; and
//! the log of what a frame recorded, pass by pass, at which level.

use wgpu_profiler::GpuProfilerQuery;

use super::targets::TargetViews;
use crate::draw::begin_pass;
use crate::profiling::GpuTimer;

/// Where a pass belongs in the chapter's Listing 1.1: once per frame, once per display,
/// or once per eye.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Level {
    /// Once per frame, whatever the displays.
    Frame,
    /// Once per display, both eyes.
    Display,
    /// Once per eye.
    Eye,
}

/// One pass a frame recorded, in recording order ([`super::Renderer::passes`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
pub struct PassRecord {
    /// How often the pass runs.
    pub level: Level,
    /// `scatter`, `coarse_cull`, `shadow_cull`, `shadow` (frame); `cull`, `far_cull`,
    /// `far_layer`, `draw` (display); `draw` (eye, the per-eye classic modes).
    pub name: &'static str,
    /// The display, for display and eye passes.
    pub display: Option<u32>,
    /// The eye, for eye passes.
    pub eye: Option<u32>,
    /// Its pipeline-statistics query in the frame's [`GpuTimer`], when counted.
    pub statistics: Option<u32>,
}

impl PassRecord {
    /// A frame pass.
    pub fn frame(name: &'static str) -> PassRecord {
        PassRecord {
            level: Level::Frame,
            name,
            display: None,
            eye: None,
            statistics: None,
        }
    }

    /// A pass of display `display`.
    pub fn display(name: &'static str, display: usize) -> PassRecord {
        PassRecord {
            level: Level::Display,
            display: Some(display as u32),
            ..PassRecord::frame(name)
        }
    }

    /// A pass of eye `eye` of display `display`.
    pub fn eye(name: &'static str, display: usize, eye: usize) -> PassRecord {
        PassRecord {
            level: Level::Eye,
            eye: Some(eye as u32),
            ..PassRecord::display(name, display)
        }
    }
}

/// Records one draw pass into `target`, clearing it or not (and in multiview or not):
/// [`render_pass`] named `draw`.
pub(super) fn draw_pass(
    encoder: &mut wgpu::CommandEncoder,
    target: &TargetViews,
    clear: bool,
    multiview_mask: Option<std::num::NonZeroU32>,
    timing: Timing,
    logged: Logged,
    record: impl FnOnce(&mut wgpu::RenderPass) -> u32,
) -> u32 {
    let begin = opener(|encoder, writes| {
        begin_pass(encoder, target.attachments(), clear, multiview_mask, writes).forget_lifetime()
    });
    render_pass(encoder, begin, (timing, logged), record)
}

/// Where a frame's passes are recorded besides the encoder: the frame's timer, if any,
/// and the pass log.
pub(super) struct Recording<'a, 'b> {
    pub(super) timer: &'a mut Option<&'b mut GpuTimer>,
    pub(super) log: &'a mut Vec<PassRecord>,
}

impl<'b> Recording<'_, 'b> {
    /// The same recording, for one more pass (a shorter reborrow).
    pub(super) fn again(&mut self) -> Recording<'_, 'b> {
        Recording {
            timer: &mut *self.timer,
            log: &mut *self.log,
        }
    }
}

/// The frame's timer, if any, and the scope a pass nests in.
pub(super) type Timing<'a, 'b> = (
    &'a mut Option<&'b mut GpuTimer>,
    &'a Option<GpuProfilerQuery>,
);

/// The frame's pass log, and the entry a pass adds to it.
pub(super) type Logged<'a> = (&'a mut Vec<PassRecord>, PassRecord);

/// How [`render_pass`] opens its pass: from the encoder and the scope's timestamp
/// writes. (Typing the closure here gives it the signature for every lifetime.)
pub(super) fn opener<F>(begin: F) -> F
where
    F: FnOnce(
        &mut wgpu::CommandEncoder,
        Option<wgpu::RenderPassTimestampWrites>,
    ) -> wgpu::RenderPass<'static>,
{
    begin
}

/// Records one render pass that `begin` opens (given its timestamp writes): a timer
/// scope named as `what` inside `parent`'s, and pipeline statistics around what `record`
/// draws (it returns its draw calls); logs the pass as `what`.
pub(super) fn render_pass(
    encoder: &mut wgpu::CommandEncoder,
    begin: impl FnOnce(
        &mut wgpu::CommandEncoder,
        Option<wgpu::RenderPassTimestampWrites>,
    ) -> wgpu::RenderPass<'static>,
    ((timer, parent), (log, what)): (Timing, Logged),
    record: impl FnOnce(&mut wgpu::RenderPass) -> u32,
) -> u32 {
    let scope = open_pass(timer, what.name, parent, encoder);
    let writes = scope
        .as_ref()
        .and_then(|q| q.render_pass_timestamp_writes());
    let mut pass = begin(encoder, writes);
    let statistics = timer
        .as_deref_mut()
        .and_then(|t| t.begin_statistics(&mut pass));
    let calls = record(&mut pass);
    GpuTimer::end_statistics(&mut pass, statistics.is_some());
    drop(pass);
    close(timer, encoder, scope);
    log.push(PassRecord { statistics, ..what });
    calls
}

/// Records one compute pass, timed as `what`'s name inside `parent`'s scope and logged
/// as `what`; `record` fills it.
pub(super) fn compute_pass(
    encoder: &mut wgpu::CommandEncoder,
    (timer, parent): Timing,
    (log, what): Logged,
    record: impl FnOnce(&mut wgpu::ComputePass),
) {
    let scope = open_pass(timer, what.name, parent, encoder);
    let writes = scope
        .as_ref()
        .and_then(|q| q.compute_pass_timestamp_writes());
    let label = format!("stereocull.{}", what.name);
    let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
        label: Some(&label),
        timestamp_writes: writes,
    });
    record(&mut pass);
    drop(pass);
    close(timer, encoder, scope);
    log.push(what);
}

/// Records one frame-level compute pass logged and timed as `name`, inside a `frame`
/// scope as the other frame-level passes are; `record` fills it.
pub(super) fn frame_compute_pass(
    encoder: &mut wgpu::CommandEncoder,
    Recording { timer, log }: Recording,
    name: &'static str,
    record: impl FnOnce(&mut wgpu::ComputePass),
) {
    let frame = open_display(timer, "frame", encoder);
    compute_pass(
        encoder,
        (timer, &frame),
        (log, PassRecord::frame(name)),
        record,
    );
    close(timer, encoder, frame);
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
