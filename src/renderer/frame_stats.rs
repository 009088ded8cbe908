//! What one frame recorded and uploaded, and the CPU time of its phases: what
//! `prepare`, `latch` and `encode` return, summed over a frame's parts.

use std::time::Duration;

use crate::keep::WholeRedraw;

/// What one frame recorded and uploaded, and the CPU time of its phases.
#[derive(Clone, Copy, Debug, Default, PartialEq, serde::Serialize)]
pub struct FrameStats {
    /// Draw calls recorded.
    pub draw_calls: u32,
    /// Compute dispatches recorded.
    pub dispatches: u32,
    /// The same by level: the frame's (once per frame, whatever the displays: posing,
    /// skinning, the coarse cull, the rig cull, the shadow pass) and the displays'
    /// (those culls that run per display, their pyramids).
    pub dispatch_levels: DispatchLevels,
    /// Bytes written to GPU buffers (contexts, CPU culls, texels, edits).
    pub bytes_uploaded: u64,
    /// CPU culling (zero on the GPU path).
    #[serde(skip)]
    pub cpu_cull: Duration,
    /// Writing contexts and cull results into buffers.
    #[serde(skip)]
    pub cpu_upload: Duration,
    /// Copying the last sync's edits into staging memory (in `encode`; zero without
    /// edits).
    #[serde(skip)]
    pub cpu_staging: Duration,
    /// Keeping unchanged pixels with the CPU cull: the tiles the displays redrew, as
    /// the CPU marked them (0 in a frame drawn whole, and with the GPU cull, whose
    /// marking pass finds them: read them back with
    /// [`crate::renderer::Diagnostics::tiles_changed`]).
    pub tiles_changed: u32,
    /// Why the frame was drawn whole (`None`: it kept what did not change).
    pub whole_redraw: Option<WholeRedraw>,
}

impl FrameStats {
    /// `draw_calls` and `dispatches` recorded at the display level.
    pub(super) fn display_level(draw_calls: u32, dispatches: u32) -> FrameStats {
        FrameStats {
            draw_calls,
            dispatches,
            dispatch_levels: DispatchLevels {
                frame: 0,
                display: dispatches,
            },
            ..FrameStats::default()
        }
    }

    /// What a display's passes recorded (their draw calls and dispatches), counted at
    /// the display level.
    pub(super) fn at_display_level(self) -> FrameStats {
        FrameStats::display_level(self.draw_calls, self.dispatches)
    }

    /// `dispatches` recorded at the frame level.
    pub(super) fn frame_level(dispatches: u32) -> FrameStats {
        FrameStats {
            dispatches,
            dispatch_levels: DispatchLevels {
                frame: dispatches,
                display: 0,
            },
            ..FrameStats::default()
        }
    }
}

/// A frame's compute dispatches by the level that records them.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Serialize)]
pub struct DispatchLevels {
    /// Recorded once per frame.
    pub frame: u32,
    /// Recorded per display (the sum over the displays).
    pub display: u32,
}

/// The two halves of a frame culled on the CPU with occlusion, together.
impl std::ops::Add for FrameStats {
    type Output = FrameStats;

    fn add(self, other: FrameStats) -> FrameStats {
        FrameStats {
            draw_calls: self.draw_calls + other.draw_calls,
            dispatches: self.dispatches + other.dispatches,
            dispatch_levels: DispatchLevels {
                frame: self.dispatch_levels.frame + other.dispatch_levels.frame,
                display: self.dispatch_levels.display + other.dispatch_levels.display,
            },
            bytes_uploaded: self.bytes_uploaded + other.bytes_uploaded,
            cpu_cull: self.cpu_cull + other.cpu_cull,
            cpu_upload: self.cpu_upload + other.cpu_upload,
            cpu_staging: self.cpu_staging + other.cpu_staging,
            tiles_changed: self.tiles_changed + other.tiles_changed,
            whole_redraw: self.whole_redraw.or(other.whole_redraw),
        }
    }
}
