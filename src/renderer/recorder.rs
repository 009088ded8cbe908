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

/// Where a frame's passes are recorded besides the encoder, as one value every pass
/// function takes: the frame's GPU timer (if any), the scope of the level a pass nests
/// in (a display's, `frame` or `shadow`), and the log of what the frame recorded. A pass
/// function opens its pass ([`Recorder::open`]), begins it with the writes that gives
/// and closes it ([`Recorder::close_compute`], [`Recorder::close_render`]).
pub struct Recorder<'a> {
    timer: Option<&'a mut GpuTimer>,
    /// The open level scope, when timing.
    scope: Option<GpuProfilerQuery>,
    log: Vec<PassRecord>,
}

/// A pass being recorded: its timer scope (when timing) and its log entry.
pub struct OpenPass {
    scope: Option<GpuProfilerQuery>,
    what: PassRecord,
    /// Whether it counts the samples passing depth ([`Recorder::count_samples`]).
    samples: bool,
    /// A multiview draw pass: a query there spans one index per view, which the
    /// timer's sets do not reserve, so it counts no samples.
    multiview: bool,
}

impl OpenPass {
    /// The timestamp writes of a render pass's descriptor.
    pub fn render_writes(&self) -> Option<wgpu::RenderPassTimestampWrites<'_>> {
        self.scope.as_ref()?.render_pass_timestamp_writes()
    }

    /// The compute pass it opened, begun in `encoder`.
    pub fn compute(&self, encoder: &mut wgpu::CommandEncoder) -> wgpu::ComputePass<'static> {
        let label = format!("stereocull.{}", self.what.name);
        let writes = self
            .scope
            .as_ref()
            .and_then(|q| q.compute_pass_timestamp_writes());
        encoder
            .begin_compute_pass(&wgpu::ComputePassDescriptor {
                label: Some(&label),
                timestamp_writes: writes,
            })
            .forget_lifetime()
    }
}

impl<'a> Recorder<'a> {
    /// A frame's recording, its log continuing `log` (empty for a new frame).
    pub fn new(timer: Option<&'a mut GpuTimer>, log: Vec<PassRecord>) -> Recorder<'a> {
        Recorder {
            timer,
            scope: None,
            log,
        }
    }

    /// Opens the level scope `name` (a display's name, `frame`, `shadow`) that the
    /// passes opened until [`Recorder::leave`] nest in.
    pub fn enter(&mut self, encoder: &mut wgpu::CommandEncoder, name: &str) {
        self.leave(encoder);
        self.scope = self.timer.as_deref().map(|t| t.scope(name, encoder));
    }

    /// Closes the open level scope.
    pub fn leave(&mut self, encoder: &mut wgpu::CommandEncoder) {
        if let (Some(t), Some(scope)) = (self.timer.as_deref(), self.scope.take()) {
            t.end(encoder, scope);
        }
    }

    /// Opens pass `what` inside the level scope.
    pub fn open(&self, encoder: &mut wgpu::CommandEncoder, what: PassRecord) -> OpenPass {
        let scope = match (self.timer.as_deref(), &self.scope) {
            (Some(t), Some(parent)) => Some(t.pass(what.name, parent, encoder)),
            _ => None,
        };
        OpenPass {
            scope,
            what,
            samples: false,
            multiview: false,
        }
    }

    /// One compute pass, opened as `what`, for a frame pass or a display's.
    pub fn compute_pass(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        what: PassRecord,
    ) -> (wgpu::ComputePass<'static>, OpenPass) {
        let open = self.open(encoder, what);
        (open.compute(encoder), open)
    }

    /// A frame-level compute pass `name`, alone in a `frame` scope (closed by
    /// [`Recorder::close_frame_pass`]), as the frame's passes are timed.
    pub fn frame_pass(
        &mut self,
        encoder: &mut wgpu::CommandEncoder,
        name: &'static str,
    ) -> (wgpu::ComputePass<'static>, OpenPass) {
        self.enter(encoder, "frame");
        self.compute_pass(encoder, PassRecord::frame(name))
    }

    /// Ends a [`Recorder::frame_pass`] and its scope.
    pub fn close_frame_pass(
        &mut self,
        encoder: &mut wgpu::CommandEncoder,
        pass: wgpu::ComputePass<'static>,
        open: OpenPass,
    ) {
        self.close_compute(encoder, pass, open);
        self.leave(encoder);
    }

    /// Ends compute pass `pass` of `open`: its scope closed, the pass logged.
    pub fn close_compute(
        &mut self,
        encoder: &mut wgpu::CommandEncoder,
        pass: wgpu::ComputePass<'static>,
        open: OpenPass,
    ) {
        drop(pass);
        self.close(encoder, open);
    }

    /// Counts render pass `pass` of `open` (pipeline statistics, when timing) from here
    /// to [`Recorder::close_render`].
    pub fn count(&mut self, pass: &mut wgpu::RenderPass, open: &mut OpenPass) {
        open.what.statistics = self
            .timer
            .as_deref_mut()
            .and_then(|t| t.begin_statistics(pass));
    }

    /// Counts the samples passing the depth test in draw pass `pass` of `open` (begun
    /// by [`begin_draw_pass`]), when timing, from here to [`Recorder::close_render`]:
    /// called before the scene's draws, after the lens's mask. Multiview passes are
    /// not counted.
    pub fn count_samples(&mut self, pass: &mut wgpu::RenderPass, open: &mut OpenPass) {
        let timer = self.timer.as_deref_mut().filter(|_| !open.multiview);
        open.samples = timer.is_some_and(|t| t.begin_samples(pass));
    }

    /// Ends render pass `pass` of `open`: its statistics and scope closed, the pass
    /// logged.
    pub fn close_render(
        &mut self,
        encoder: &mut wgpu::CommandEncoder,
        mut pass: wgpu::RenderPass<'static>,
        open: OpenPass,
    ) {
        GpuTimer::end_samples(&mut pass, open.samples);
        GpuTimer::end_statistics(&mut pass, open.what.statistics.is_some());
        drop(pass);
        self.close(encoder, open);
    }

    fn close(&mut self, encoder: &mut wgpu::CommandEncoder, open: OpenPass) {
        if let (Some(t), Some(scope)) = (self.timer.as_deref(), open.scope) {
            t.end(encoder, scope);
        }
        self.log.push(open.what);
    }

    /// Logs a pass recorded without a scope of its own (the scatter of edits).
    pub fn log(&mut self, what: PassRecord) {
        self.log.push(what);
    }

    /// The recording's end: the level scope closed, with `resolve` the timer's queries
    /// resolved into `encoder`; returns the log.
    pub fn finish(mut self, encoder: &mut wgpu::CommandEncoder, resolve: bool) -> Vec<PassRecord> {
        self.leave(encoder);
        if let Some(t) = self.timer.filter(|_| resolve) {
            t.resolve(encoder);
        }
        self.log
    }
}

/// Begins the draw pass into `target`, clearing it or not (and in multiview or not),
/// for `open`, counted.
pub fn begin_draw_pass(
    encoder: &mut wgpu::CommandEncoder,
    rec: &mut Recorder,
    target: &TargetViews,
    clear: bool,
    multiview_mask: Option<std::num::NonZeroU32>,
    open: &mut OpenPass,
) -> wgpu::RenderPass<'static> {
    open.multiview = multiview_mask.is_some();
    let queries = (
        open.render_writes(),
        rec.timer.as_deref().map(GpuTimer::sample_queries),
    );
    let mut pass = begin_pass(
        encoder,
        target.attachments(),
        clear,
        multiview_mask,
        queries,
    )
    .forget_lifetime();
    rec.count(&mut pass, open);
    pass
}
