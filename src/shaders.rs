//! WGSL composition, in one place: every pipeline's source is its file in `wgsl/` after
//! the shared includes and the constants injected from Rust.

/// Invocations per cull workgroup: one instance each, and the scan's shared array holds
/// one entry per invocation. 256 is the largest size every WebGPU adapter must support.
pub const WORKGROUP_SIZE: u32 = 256;

const CONTEXTS: &str = include_str!("../wgsl/shared/contexts.wgsl");
const RECORDS: &str = include_str!("../wgsl/shared/records.wgsl");
const CULL_MATH: &str = include_str!("../wgsl/shared/cull_math.wgsl");
const DRAW_CLIP_DISTANCES: &str = include_str!("../wgsl/shared/draw_clip_distances.wgsl");
const DRAW_NO_CLIP_DISTANCES: &str = include_str!("../wgsl/shared/draw_no_clip_distances.wgsl");
const DRAW_COMMON: &str = include_str!("../wgsl/shared/draw_common.wgsl");
const DRAW: &str = include_str!("../wgsl/draw.wgsl");
const DRAW_MULTIVIEW: &str = include_str!("../wgsl/draw_multiview.wgsl");

/// The three per-display cull passes, in dispatch order.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum CullPass {
    /// Sphere tests, flags and per-workgroup prefixes.
    Cull,
    /// Block prefixes, then the packed draws and the draw count (one workgroup).
    Draws,
    /// Visible ids into their slots.
    Compact,
}

impl CullPass {
    pub const ALL: [CullPass; 3] = [CullPass::Cull, CullPass::Draws, CullPass::Compact];

    pub fn label(self) -> &'static str {
        match self {
            CullPass::Cull => "stereocull.cull",
            CullPass::Draws => "stereocull.cull_draws",
            CullPass::Compact => "stereocull.cull_compact",
        }
    }

    pub fn entry_point(self) -> &'static str {
        match self {
            CullPass::Cull => "cull",
            CullPass::Draws => "draws_main",
            CullPass::Compact => "compact",
        }
    }

    pub fn source(self) -> String {
        let body = match self {
            CullPass::Cull => include_str!("../wgsl/cull.wgsl"),
            CullPass::Draws => include_str!("../wgsl/cull_draws.wgsl"),
            CullPass::Compact => include_str!("../wgsl/cull_compact.wgsl"),
        };
        [&constants(2), CONTEXTS, RECORDS, CULL_MATH, body].concat()
    }
}

/// Names a draw-pipeline variant; produces its source and a readable label.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct DrawKey {
    /// 2: doubled instances into a double-wide target; 1: one view.
    pub views: u32,
    /// Hardware clip distances at the seam, or a fragment discard.
    pub clip_distances: bool,
    /// One view per instance into a two-layer target, the eye from `view_index`.
    pub multiview: bool,
}

impl DrawKey {
    /// Every variant, for validation.
    pub const ALL: [DrawKey; 4] = [
        DrawKey::new(2, true),
        DrawKey::new(2, false),
        DrawKey::new(1, false),
        DrawKey::MULTIVIEW,
    ];

    pub const MULTIVIEW: DrawKey = DrawKey {
        views: 1,
        clip_distances: false,
        multiview: true,
    };

    /// The variant for `views` on a device with or without clip distances (one view
    /// never needs them).
    pub const fn new(views: u32, clip_distances_available: bool) -> DrawKey {
        DrawKey {
            views,
            clip_distances: views == 2 && clip_distances_available,
            multiview: false,
        }
    }

    pub fn label(self) -> String {
        let seam = if self.clip_distances {
            "clip"
        } else {
            "discard"
        };
        match (self.multiview, self.views) {
            (true, _) => "stereocull.draw.multiview".into(),
            (false, 1) => "stereocull.draw.mono".into(),
            _ => format!("stereocull.draw.stereo.{seam}"),
        }
    }

    pub fn source(self) -> String {
        let prelude = if self.clip_distances {
            DRAW_CLIP_DISTANCES
        } else {
            DRAW_NO_CLIP_DISTANCES
        };
        let entry = if self.multiview { DRAW_MULTIVIEW } else { DRAW };
        [
            prelude,
            &constants(self.views),
            CONTEXTS,
            RECORDS,
            DRAW_COMMON,
            entry,
        ]
        .concat()
    }
}

fn constants(views: u32) -> String {
    format!("\nconst WORKGROUP_SIZE: u32 = {WORKGROUP_SIZE}u;\nconst VIEWS: u32 = {views}u;\n")
}

/// Every shader variant the crate can build, with its label.
pub fn all_sources() -> Vec<(String, String)> {
    let cull = CullPass::ALL.map(|p| (p.label().to_string(), p.source()));
    let draw = DrawKey::ALL.map(|k| (k.label(), k.source()));
    cull.into_iter().chain(draw).collect()
}
