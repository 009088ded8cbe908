//! Measurement: GPU timestamps around each pass (wgpu-profiler: one scope per display,
//! a nested scope per pass, and a Chrome trace of a frame for free), pipeline
//! statistics over the draw passes (which wgpu-profiler does not gather), and the
//! percentiles the reports use.

use std::path::Path;

use wgpu_profiler::{GpuProfiler, GpuProfilerQuery, GpuProfilerSettings, GpuTimerQueryResult};

use crate::error::{Error, Result};
use crate::readback::{read_pod, wait_idle};

/// Timestamp scopes around passes, resolved once per frame. `None` from [`GpuTimer::new`]
/// when the device has no `TIMESTAMP_QUERY`: reports then say so instead of printing zeros.
pub struct GpuTimer {
    profiler: GpuProfiler,
    /// Nanoseconds per timestamp tick.
    period: f32,
    /// Vertex-shader invocations and clipper primitives per draw pass, where the
    /// device has `PIPELINE_STATISTICS_QUERY`.
    statistics: Option<Queries>,
    /// Samples that passed the depth test in the display draws (occlusion queries),
    /// one per display draw pass, each from its first scene draw (after the lens's
    /// mask) to its end.
    samples: Queries,
    /// The last frame read, as wgpu-profiler's scope tree (for traces).
    last: Vec<GpuTimerQueryResult>,
}

/// One kind of query, one per draw pass of a frame, and the buffer they resolve into.
struct Queries {
    queries: wgpu::QuerySet,
    resolved: wgpu::Buffer,
    /// Counts each query writes.
    values: usize,
    capacity: u32,
    used: u32,
}

impl Queries {
    fn new(
        device: &wgpu::Device,
        label: &str,
        (ty, values): (wgpu::QueryType, usize),
        passes: u32,
    ) -> Queries {
        Queries {
            queries: device.create_query_set(&wgpu::QuerySetDescriptor {
                label: Some(label),
                ty,
                count: passes,
            }),
            resolved: device.create_buffer(&wgpu::BufferDescriptor {
                label: Some(label),
                size: (8 * values) as u64 * passes as u64,
                usage: wgpu::BufferUsages::QUERY_RESOLVE | wgpu::BufferUsages::COPY_SRC,
                mapped_at_creation: false,
            }),
            values,
            capacity: passes,
            used: 0,
        }
    }

    /// The next query's index, if the frame has room for one more.
    fn take(&mut self) -> Option<u32> {
        (self.used < self.capacity).then(|| {
            self.used += 1;
            self.used - 1
        })
    }

    fn resolve(&self, encoder: &mut wgpu::CommandEncoder) {
        if self.used > 0 {
            encoder.resolve_query_set(&self.queries, 0..self.used, &self.resolved, 0);
        }
    }

    /// The frame's counts, `values` per query in order (none when no query ran);
    /// resets for the next frame.
    fn read(&mut self, device: &wgpu::Device, queue: &wgpu::Queue) -> Result<Vec<u64>> {
        let used = std::mem::take(&mut self.used);
        match used {
            0 => Ok(Vec::new()),
            n => read_pod(
                device,
                queue,
                &self.resolved,
                (8 * self.values) as u64 * n as u64,
            ),
        }
    }
}

/// What the GPU reported for one frame.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct FrameQueries {
    /// Milliseconds per pass label (`cull`, `draw`), summed over displays.
    pub passes: Vec<(String, f64)>,
    /// Summed over the draw passes; `None` without pipeline statistics.
    pub vertex_invocations: Option<u64>,
    /// Per statistics query of the frame, in order (`PassRecord::statistics` says which
    /// pass each counted).
    pub vertex_invocations_per_query: Vec<u64>,
    /// Primitives that reached the clipper: the triangles submitted.
    pub triangles_submitted: Option<u64>,
    /// Primitives the clipper passed on.
    pub clipper_primitives: Option<u64>,
    /// Fragment-shader invocations: the pixels (samples, under per-sample shading)
    /// shaded, which a foveated display's smaller views cut.
    pub fragment_invocations: Option<u64>,
    /// Samples of the display draws that passed the depth test (occlusion queries,
    /// from each pass's first scene draw, so the lens's mask is not counted): what a
    /// GPU that tests depth before shading shades of opaque surfaces, where lavapipe's
    /// `fragment_invocations` count before its depth test. Multiview passes are not
    /// counted; `None` when no pass was.
    pub samples_passed: Option<u64>,
}

/// The statistics gathered; query results list them in bit order.
const STATISTICS: wgpu::PipelineStatisticsTypes =
    wgpu::PipelineStatisticsTypes::VERTEX_SHADER_INVOCATIONS
        .union(wgpu::PipelineStatisticsTypes::CLIPPER_INVOCATIONS)
        .union(wgpu::PipelineStatisticsTypes::CLIPPER_PRIMITIVES_OUT)
        .union(wgpu::PipelineStatisticsTypes::FRAGMENT_SHADER_INVOCATIONS);
const STATISTICS_PER_QUERY: usize = 4;

impl GpuTimer {
    /// Room for pipeline statistics over `passes` draw passes per frame (timestamps
    /// grow as needed).
    pub fn new(device: &wgpu::Device, queue: &wgpu::Queue, passes: u32) -> Option<GpuTimer> {
        if !device.features().contains(wgpu::Features::TIMESTAMP_QUERY) {
            return None;
        }
        let settings = GpuProfilerSettings {
            // One frame is read back before the next is recorded.
            max_num_pending_frames: 1,
            enable_debug_groups: false,
            ..Default::default()
        };
        let profiler = GpuProfiler::new(device, settings).ok()?;
        let statistics = device
            .features()
            .contains(wgpu::Features::PIPELINE_STATISTICS_QUERY)
            .then(|| {
                let kind = (
                    wgpu::QueryType::PipelineStatistics(STATISTICS),
                    STATISTICS_PER_QUERY,
                );
                Queries::new(device, "stereocull.pipeline_statistics", kind, passes)
            });
        let occlusion = (wgpu::QueryType::Occlusion, 1);
        Some(GpuTimer {
            profiler,
            period: queue.get_timestamp_period(),
            statistics,
            samples: Queries::new(device, "stereocull.samples_passed", occlusion, passes),
            last: Vec::new(),
        })
    }

    /// Opens a scope on the encoder (one display), for passes to nest in; close it
    /// with [`GpuTimer::end`].
    pub fn scope(&self, label: &str, encoder: &mut wgpu::CommandEncoder) -> GpuProfilerQuery {
        self.profiler.begin_query(label, encoder)
    }

    /// A scope for one pass inside `parent`: its timestamp writes go into the pass
    /// descriptor; close it with [`GpuTimer::end`] after the pass.
    pub fn pass(
        &self,
        label: &str,
        parent: &GpuProfilerQuery,
        encoder: &mut wgpu::CommandEncoder,
    ) -> GpuProfilerQuery {
        self.profiler
            .begin_pass_query(label, encoder)
            .with_parent(Some(parent))
    }

    /// Closes `query`, a scope or pass opened by this timer.
    pub fn end(&self, encoder: &mut wgpu::CommandEncoder, query: GpuProfilerQuery) {
        self.profiler.end_query(encoder, query);
    }

    /// Starts counting vertex invocations and clipped primitives in `pass`; returns
    /// the query's index in the frame when it did (then [`GpuTimer::end_statistics`]
    /// must follow in the same pass).
    pub fn begin_statistics(&mut self, pass: &mut wgpu::RenderPass) -> Option<u32> {
        let s = self.statistics.as_mut()?;
        let index = s.take()?;
        pass.begin_pipeline_statistics_query(&s.queries, index);
        Some(index)
    }

    /// Ends the statistics query [`GpuTimer::begin_statistics`] began in `pass`, if it did.
    pub fn end_statistics(pass: &mut wgpu::RenderPass, begun: bool) {
        if begun {
            pass.end_pipeline_statistics_query();
        }
    }

    /// The occlusion query set a draw pass's descriptor names, for
    /// [`GpuTimer::begin_samples`] in that pass.
    pub fn sample_queries(&self) -> &wgpu::QuerySet {
        &self.samples.queries
    }

    /// Starts counting the samples that pass the depth test in `pass` (begun with
    /// [`GpuTimer::sample_queries`]); returns whether it did (then
    /// [`GpuTimer::end_samples`] must follow in the same pass).
    pub fn begin_samples(&mut self, pass: &mut wgpu::RenderPass) -> bool {
        let index = self.samples.take();
        if let Some(index) = index {
            pass.begin_occlusion_query(index);
        }
        index.is_some()
    }

    /// Ends the count [`GpuTimer::begin_samples`] began in `pass`, if it did.
    pub fn end_samples(pass: &mut wgpu::RenderPass, begun: bool) {
        if begun {
            pass.end_occlusion_query();
        }
    }

    /// Records the resolve of this frame's queries; call once, after the last pass.
    pub fn resolve(&mut self, encoder: &mut wgpu::CommandEncoder) {
        self.profiler.resolve_queries(encoder);
        if let Some(s) = &self.statistics {
            s.resolve(encoder);
        }
        self.samples.resolve(encoder);
    }

    /// The submitted frame's pass times (summed by label) and statistics; resets for the
    /// next frame. Call after the frame's submission.
    pub fn read(&mut self, device: &wgpu::Device, queue: &wgpu::Queue) -> Result<FrameQueries> {
        self.profiler
            .end_frame()
            .map_err(|e| Error::Readback(format!("GPU timer: {e}")))?;
        wait_idle(device)?;
        self.last = self
            .profiler
            .process_finished_frame(self.period)
            .ok_or_else(|| {
                Error::Readback("GPU timer: the frame's timestamps did not map".into())
            })?;
        let mut frame = FrameQueries::default();
        sum_passes(&self.last, &mut frame.passes);
        if let Some(s) = self.statistics.as_mut() {
            let counts = s.read(device, queue)?;
            let sum = |k: usize| Some(counts.iter().skip(k).step_by(STATISTICS_PER_QUERY).sum());
            frame.vertex_invocations = sum(0);
            frame.vertex_invocations_per_query = counts
                .iter()
                .step_by(STATISTICS_PER_QUERY)
                .copied()
                .collect();
            frame.triangles_submitted = sum(1);
            frame.clipper_primitives = sum(2);
            frame.fragment_invocations = sum(3);
        }
        let passed = self.samples.read(device, queue)?;
        frame.samples_passed = (!passed.is_empty()).then(|| passed.iter().sum());
        Ok(frame)
    }

    /// The scopes of the last frame read: one per display, its passes nested.
    pub fn last_frame(&self) -> &[GpuTimerQueryResult] {
        &self.last
    }
}

/// Writes frames as one Chrome trace (`chrome://tracing`, Perfetto): each frame a scope
/// named by its label, spanning its displays' scopes and their passes.
pub fn write_trace(path: &Path, frames: Vec<(String, Vec<GpuTimerQueryResult>)>) -> Result<()> {
    let scopes: Vec<_> = frames
        .into_iter()
        .map(|(label, nested)| {
            let (start, end) = span(&nested, (f64::MAX, f64::MIN));
            GpuTimerQueryResult {
                label,
                pid: std::process::id(),
                tid: std::thread::current().id(),
                time: (start <= end).then_some(start..end),
                nested_queries: nested,
            }
        })
        .collect();
    wgpu_profiler::chrometrace::write_chrometrace(path, &scopes).map_err(|e| Error::io(path, e))
}

/// The earliest start and latest end of `scopes` and everything nested in them.
fn span(scopes: &[GpuTimerQueryResult], mut range: (f64, f64)) -> (f64, f64) {
    for scope in scopes {
        if let Some(t) = &scope.time {
            range = (range.0.min(t.start), range.1.max(t.end));
        }
        range = span(&scope.nested_queries, range);
    }
    range
}

/// Milliseconds of the leaf scopes (the passes), summed by label.
fn sum_passes(scopes: &[GpuTimerQueryResult], out: &mut Vec<(String, f64)>) {
    for scope in scopes {
        if !scope.nested_queries.is_empty() {
            sum_passes(&scope.nested_queries, out);
            continue;
        }
        let ms = scope.time.as_ref().map_or(0.0, |t| (t.end - t.start) * 1e3);
        match out.iter_mut().find(|(l, _)| *l == scope.label) {
            Some((_, t)) => *t += ms,
            None => out.push((scope.label.clone(), ms)),
        }
    }
}

/// Nearest-rank percentile of unsorted samples (`q` in 0..=1); 0 for no samples.
pub fn percentile(samples: &[f64], q: f64) -> f64 {
    if samples.is_empty() {
        return 0.0;
    }
    let mut sorted = samples.to_vec();
    sorted.sort_by(f64::total_cmp);
    let rank = ((q * sorted.len() as f64).ceil() as usize).clamp(1, sorted.len());
    sorted[rank - 1]
}
