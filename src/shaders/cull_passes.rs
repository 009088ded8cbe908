//! The culling family's WGSL: the cull passes (frame, display, each display pass in its
//! occlusion phase, the floor kernel), which tier of the cull pass a device runs, and
//! the occlusion pyramids' passes. Composed from the includes and constants of
//! [`super`] and the binding lists of `bindings.rs`.

use super::binding_lists::{PYRAMID_SET_DEPTHS, PYRAMID_SET_SLICES, pyramid_bindings};
use super::bindings::declarations;
use super::{
    CANDIDATE_BINDINGS, COARSE_BINDINGS, CONTEXTS, CULL_BINDINGS, CULL_MATH, CULL_SUBGROUPS, KEEP,
    MAX_RIG_VIEWS, OCCLUSION, PYRAMID, RECORDS, SPHERE_PIXELS, WORKGROUP_SIZE, Windows, constants,
};
use crate::scene::MAX_LODS;

const OVER_EVERYTHING: &str = include_str!("../../wgsl/shared/over_everything.wgsl");
const OVER_CANDIDATES: &str = include_str!("../../wgsl/shared/over_candidates.wgsl");

/// Which part of a display's two-phase cull a cull pass runs (`OCCLUSION` in
/// `wgsl/shared/occlusion.wgsl`; see [`crate::occlusion`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Phase {
    /// The frustum alone: occlusion off, or a view without it.
    Frustum = 0,
    /// What the display drew last frame (and the frustum keeps), drawn first.
    Early = 1,
    /// What it did not, unless the early depth's pyramids hide it; records for the next
    /// frame what the pyramids do not hide.
    Late = 2,
    /// What the display's pyramids do not hide, whatever it drew last frame, recording
    /// nothing: a far layer's cull after its display's early phase (the far layer is
    /// drawn once per frame from this frame's depth, so it has no phases of its own).
    Tested = 3,
}

impl Phase {
    /// A pipeline's label in this phase.
    pub fn label(self, base: &str) -> String {
        match self {
            Phase::Frustum => base.to_string(),
            Phase::Early => format!("{base}.early"),
            Phase::Late => format!("{base}.late"),
            Phase::Tested => format!("{base}.tested"),
        }
    }
}

/// The cull passes: three at the frame level (the coarse cull, when on) and three per
/// display (a fourth with blended bins), each list in dispatch order; and the floor kernel `profile` times beside them.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum CullPass {
    /// Every block's sphere (a block per invocation), tested against the frame frustum
    /// and each slot's: marks, and per slot each workgroup's kept blocks.
    CoarseBlocks,
    /// Per slot (one workgroup each): prefixes of the workgroups' totals, each mesh's
    /// range among the listed positions, the count and the display passes' indirect
    /// dispatches.
    CoarseLists,
    /// Per slot, each kept block into the slot's list (a block per invocation).
    CoarsePlace,
    /// Sphere tests and levels, once per sphere, a span per invocation: entries, span
    /// prefixes within their workgroup and each workgroup's totals.
    Cull,
    /// [`CullPass::Cull`] with its workgroup scan done by subgroup operations: the
    /// same buffers, on adapters with one subgroup size ([`subgroup_tier`]).
    CullSubgroups,
    /// Group prefixes, then the packed draws and the draw count (one workgroup).
    Draws,
    /// Visible ids into their slots.
    Compact,
    /// With blended material bins: each visible blended instance its own draw, sorted
    /// back to front (one workgroup).
    Blend,
    /// One read and one flag per instance: the least a cull could do (`profile`).
    Floor,
    /// The rig cull's [`CullPass::Cull`]: every member's entries and sums, each sphere
    /// read once for the rig.
    RigCull,
    /// [`CullPass::Draws`] for every member (a workgroup each).
    RigDraws,
    /// [`CullPass::Compact`] for every member, a span per invocation.
    RigCompact,
    /// [`CullPass::Blend`] for every member (a workgroup each).
    RigBlend,
    /// [`CullPass::Floor`] for the rig: one read per instance, every member's test.
    RigFloor,
}

impl CullPass {
    /// The frame passes (the coarse cull), in dispatch order.
    pub const FRAME: [CullPass; 3] = [
        CullPass::CoarseBlocks,
        CullPass::CoarseLists,
        CullPass::CoarsePlace,
    ];
    /// The display passes, in dispatch order.
    pub const DISPLAY: [CullPass; 3] = [CullPass::Cull, CullPass::Draws, CullPass::Compact];
    /// The rig passes, in dispatch order: the display passes for every member at once.
    pub const RIG: [CullPass; 3] = [CullPass::RigCull, CullPass::RigDraws, CullPass::RigCompact];

    /// The pipeline's label; display passes over the coarse cull's candidates say so.
    pub fn label(self, over_candidates: bool) -> String {
        let name = match self {
            CullPass::CoarseBlocks => "coarse_blocks",
            CullPass::CoarseLists => "coarse_lists",
            CullPass::CoarsePlace => "coarse_place",
            CullPass::Cull => "cull",
            CullPass::CullSubgroups => "cull_subgroups",
            CullPass::Draws => "cull_draws",
            CullPass::Compact => "cull_compact",
            CullPass::Blend => "cull_blend",
            CullPass::Floor => "cull_floor",
            CullPass::RigCull => "rig_cull",
            CullPass::RigDraws => "rig_draws",
            CullPass::RigCompact => "rig_compact",
            CullPass::RigBlend => "rig_blend",
            CullPass::RigFloor => "rig_floor",
        };
        let tail = if over_candidates && !self.is_frame() {
            ".candidates"
        } else {
            ""
        };
        format!("stereocull.{name}{tail}")
    }

    /// Whether the pass runs once per frame.
    pub fn is_frame(self) -> bool {
        Self::FRAME.contains(&self)
    }

    /// Whether the pass is one of the rig cull's (every member of `RigCull` at once).
    pub fn is_rig(self) -> bool {
        matches!(
            self,
            CullPass::RigCull
                | CullPass::RigDraws
                | CullPass::RigCompact
                | CullPass::RigBlend
                | CullPass::RigFloor
        )
    }

    /// The pass's WGSL entry point.
    pub fn entry_point(self) -> &'static str {
        match self {
            CullPass::CoarseBlocks => "coarse_blocks",
            CullPass::CoarseLists => "coarse_lists",
            CullPass::CoarsePlace => "coarse_place",
            CullPass::Cull => "cull",
            CullPass::CullSubgroups => "cull_subgroups",
            CullPass::Draws => "draws_main",
            CullPass::Compact => "compact",
            CullPass::Blend => "blend_main",
            CullPass::Floor => "floor",
            CullPass::RigCull => "cull_rig",
            CullPass::RigDraws => "draws_rig",
            CullPass::RigCompact => "compact_rig",
            CullPass::RigBlend => "blend_rig",
            CullPass::RigFloor => "floor_rig",
        }
    }

    /// The pass's source for the pipeline `key` describes.
    pub fn source(self, key: CullKey, windows: &Windows) -> String {
        let body = match self {
            CullPass::CoarseBlocks | CullPass::CoarseLists | CullPass::CoarsePlace => {
                include_str!("../../wgsl/cull_coarse.wgsl")
            }
            CullPass::Cull | CullPass::RigCull => include_str!("../../wgsl/cull.wgsl"),
            CullPass::CullSubgroups => CULL_SUBGROUPS,
            CullPass::Draws | CullPass::RigDraws => include_str!("../../wgsl/cull_draws.wgsl"),
            CullPass::Compact | CullPass::RigCompact => {
                include_str!("../../wgsl/cull_compact.wgsl")
            }
            CullPass::Blend | CullPass::RigBlend => include_str!("../../wgsl/cull_blend.wgsl"),
            CullPass::Floor | CullPass::RigFloor => include_str!("../../wgsl/cull_floor.wgsl"),
        };
        let candidates = key.over_candidates && !self.is_frame();
        let keyed = format!(
            "const OCCLUSION: u32 = {}u;\nconst RIG: bool = {};\n{}",
            key.phase as u32,
            self.is_rig(),
            key.tests.constants(),
        );
        let rig_scans = match self {
            CullPass::Cull | CullPass::RigCull | CullPass::CullSubgroups => key.rig_scans(),
            _ => String::new(),
        };
        let mut bindings = declarations(&CULL_BINDINGS, 0, windows);
        let whole = &Windows::WHOLE;
        let over = match (self.is_frame(), candidates) {
            (true, _) => {
                bindings += &declarations(&COARSE_BINDINGS, 1, whole);
                OVER_EVERYTHING
            }
            (false, true) => {
                bindings += &declarations(&CANDIDATE_BINDINGS, 1, whole);
                OVER_CANDIDATES
            }
            (false, false) => OVER_EVERYTHING,
        };
        [
            &constants(),
            &keyed,
            CONTEXTS,
            RECORDS,
            &bindings,
            SPHERE_PIXELS,
            CULL_MATH,
            over,
            PYRAMID,
            OCCLUSION,
            KEEP,
            body,
            &rig_scans,
        ]
        .concat()
    }

    /// The cull passes' occlusion variants: both tiers and the rig's, over everything
    /// and over candidates (the rig's over everything), early, late and tested, with
    /// every test.
    pub fn occlusion_variants() -> Vec<(CullPass, CullKey)> {
        let phases = [Phase::Early, Phase::Late, Phase::Tested];
        Self::cull_passes_over()
            .flat_map(|(p, c)| phases.map(|phase| (p, CullKey::over(c).in_phase(phase))))
            .collect()
    }

    /// The cull passes without their optional tests ([`CullTests::NONE`]): both tiers
    /// and the rig's, over everything and over candidates, with one member.
    pub fn bare_variants() -> Vec<(CullPass, CullKey)> {
        Self::cull_passes_over()
            .map(|(p, c)| {
                let key = CullKey {
                    tests: CullTests::NONE,
                    rig_fields: MAX_LODS as u32,
                    ..CullKey::over(c)
                };
                (p, key)
            })
            .collect()
    }

    /// The passes that test spheres (both tiers and the rig's), each over everything
    /// and (the display's) over candidates.
    fn cull_passes_over() -> impl Iterator<Item = (CullPass, bool)> {
        let passes = [CullPass::Cull, CullPass::CullSubgroups, CullPass::RigCull];
        (passes.into_iter())
            .flat_map(|p| [false, true].map(|c| (p, c)))
            .filter(|(p, c)| !(p.is_rig() && *c))
    }

    /// Every cull pipeline variant: the frame passes, the display passes (both tiers
    /// of the cull pass) over everything and over candidates, the floor kernel, and the
    /// rig passes.
    pub fn variants() -> Vec<(CullPass, bool)> {
        let display = [false, true].into_iter().flat_map(|c| {
            Self::DISPLAY
                .into_iter()
                .chain([CullPass::CullSubgroups, CullPass::Blend])
                .map(move |p| (p, c))
        });
        Self::FRAME
            .map(|p| (p, false))
            .into_iter()
            .chain(display)
            .chain([(CullPass::Floor, false)])
            .chain(Self::RIG.map(|p| (p, false)))
            .chain([(CullPass::RigBlend, false), (CullPass::RigFloor, false)])
            .collect()
    }
}

/// The cull's optional tests, each in a pipeline only where a frame of its renderer can
/// use it: `TEST_HIDDEN`, `TEST_TILES`, `TEST_EARLY` and `TEST_SPLIT` in the WGSL.
/// A test the pipeline holds still reads its view's flag (a display without a mask
/// skips the mask's test); one it does not hold is compiled out. A runtime flag alone
/// is no saving on lavapipe, which runs a branch's body under a mask for every lane
/// even where no lane takes it: the mask's and the tiles' tests project each sphere
/// into both eyes, and cost `hmd`'s cull at 1M instances 80 of its 230 ms.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub struct CullTests {
    /// The lens's hidden area (a context's `hidden & CULL_HIDDEN`).
    pub hidden: bool,
    /// A kept frame's changed tiles (`hidden & CULL_TILES`).
    pub tiles: bool,
    /// The rig cull's early occlusion members (a member's `early`): what its display
    /// drew last frame.
    pub early: bool,
    /// The far layer's split (a context's `split_keep`).
    pub split: bool,
}

impl CullTests {
    /// Every test: what shader validation covers, and what a renderer with every
    /// feature builds.
    pub const ALL: CullTests = CullTests {
        hidden: true,
        tiles: true,
        early: true,
        split: true,
    };
    /// None: the frustum and the levels of detail alone.
    pub const NONE: CullTests = CullTests {
        hidden: false,
        tiles: false,
        early: false,
        split: false,
    };

    fn constants(self) -> String {
        format!(
            "const TEST_HIDDEN: bool = {};\nconst TEST_TILES: bool = {};\n\
             const TEST_EARLY: bool = {};\nconst TEST_SPLIT: bool = {};\n",
            self.hidden, self.tiles, self.early, self.split
        )
    }
}

/// What one cull pipeline is built for besides its pass.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct CullKey {
    /// A display pass over the frame's coarse cull candidates (else every position).
    pub over_candidates: bool,
    /// The occlusion phase (which only the cull pass reads).
    pub phase: Phase,
    /// The optional tests it holds.
    pub tests: CullTests,
    /// The rig cull's (member, level) fields: the most members one set of its
    /// dispatches culls times the levels of detail.
    pub rig_fields: u32,
}

impl CullKey {
    /// A display pass over every position or `over_candidates`, in the frustum phase,
    /// with every test and room for the most rig fields.
    pub fn over(over_candidates: bool) -> CullKey {
        CullKey {
            over_candidates,
            phase: Phase::Frustum,
            tests: CullTests::ALL,
            rig_fields: (MAX_RIG_VIEWS * MAX_LODS) as u32,
        }
    }

    /// The same key in occlusion `phase`.
    pub fn in_phase(self, phase: Phase) -> CullKey {
        CullKey { phase, ..self }
    }

    /// `scan_rig` (wgsl/cull.wgsl): the workgroup scans of the rig's fields, eight a
    /// scan, written out one call per scan. lavapipe runs barriers inside a loop at
    /// about twice their cost in straight code (`hmd`'s rig cull pass at 1M: 132 ms
    /// with the loop, 93 without), so the scans are as many calls as the key's fields
    /// need.
    fn rig_scans(self) -> String {
        let calls: String = (0..self.rig_fields.div_ceil(RIG_FIELDS_PER_SCAN))
            .map(|k| {
                let base = k * RIG_FIELDS_PER_SCAN;
                format!("    scan_rig_fields({base}u, group, local, n, levels);\n")
            })
            .collect();
        format!("\nfn scan_rig(group: u32, local: u32, n: u32, levels: u32) {{\n{calls}}}\n")
    }
}

/// (member, level) fields one workgroup scan of the rig cull carries: four words of two
/// 16-bit counts.
const RIG_FIELDS_PER_SCAN: u32 = 8;

/// Whether the cull pass runs its subgroup tier on `device`: subgroup operations, and
/// one subgroup size that divides [`WORKGROUP_SIZE`], so that every workgroup is made
/// of full subgroups of that size (what `wgsl/cull_subgroups.wgsl` needs). Adapters
/// whose size varies (AMD: 32 or 64) take the workgroup-memory scan.
pub fn subgroup_tier(device: &wgpu::Device) -> bool {
    let info = device.adapter_info();
    let size = info.subgroup_min_size;
    device.features().contains(wgpu::Features::SUBGROUP)
        && size == info.subgroup_max_size
        && size > 0
        && WORKGROUP_SIZE.is_multiple_of(size)
}

/// Levels one dispatch of `wgsl/occlusion_pyramid.wgsl` writes: a workgroup of
/// [`PYRAMID_SIDE`]² invocations reduces a tile of its first level, twice as wide, to
/// one texel. One dispatch more costs the CPU a flush of bindings and a barrier in
/// wgpu, more than the GPU work of these small levels.
pub const PYRAMID_LEVELS_PER_DISPATCH: u32 = 6;
/// Invocations per side of a pyramid workgroup: 2^(levels per dispatch - 2).
pub const PYRAMID_SIDE: u32 = 1 << (PYRAMID_LEVELS_PER_DISPATCH - 2);

/// The depth pyramid's passes (`wgsl/occlusion_pyramid.wgsl`) over a set of `depths`
/// depth targets of `samples` samples per pixel, `layered` (multiview: a layer per eye)
/// or not (the eyes side by side); its bindings are [`super::pyramid_bindings`].
/// WebGPU has no multisampled array textures, so a layered target has one sample.
pub fn pyramid_source(samples: u32, layered: bool, depths: usize) -> String {
    let (target, read) = match (samples, layered) {
        (_, true) => ("texture_depth_2d_array", "textureLoad(depth, p, s.eye, 0)"),
        (1, false) => ("texture_depth_2d", "textureLoad(depth, p, 0)"),
        // Every sample, the farthest kept.
        _ => ("texture_depth_multisampled_2d", "farthest_sample(depth, p)"),
    };
    // The slice's binding, chosen once per invocation (for its 16 pixels), not per
    // pixel: lavapipe runs a switch's every case under a mask, every binding's loads
    // where one would do (a loop of at most one turn per binding measured no better);
    // a set of one target has no choice to make (lavapipe: 32 against 46 ms a frame
    // on `hmd` at 1440 x 1600).
    let cases: String = (0..depths.clamp(1, PYRAMID_SET_DEPTHS))
        .map(|k| {
            format!(
                "        case {k}u: {{\n            return block_texels(depth{k}, at, s);\n        }}\n"
            )
        })
        .collect();
    let choose = match depths {
        0 | 1 => "return block_texels(depth0, at, s);".to_string(),
        _ => format!(
            "switch s.depth {{\n{cases}        default: {{\n            return vec4(1.0);\n        }}\n    }}"
        ),
    };
    let bindings = format!(
        "const SAMPLES: i32 = {samples};\n\
         const LEVELS_PER_DISPATCH: u32 = {PYRAMID_LEVELS_PER_DISPATCH}u;\n\
         const SIDE: u32 = {PYRAMID_SIDE}u;\n\
         const MAX_SLICES: u32 = {PYRAMID_SET_SLICES}u;\n\
         alias DepthTarget = {target};\n\
         fn read_depth(depth: DepthTarget, p: vec2<u32>, s: PyramidSlice) -> f32 {{\n    return {read};\n}}\n\
         fn depth_texels(at: vec2<u32>, s: PyramidSlice) -> vec4<f32> {{\n    \
         {choose}\n}}\n"
    );
    let declared = declarations(
        &pyramid_bindings(samples, layered, depths),
        0,
        &Windows::WHOLE,
    );
    let body = include_str!("../../wgsl/occlusion_pyramid.wgsl");
    [&declared, PYRAMID, body, &bindings].concat()
}
