//! The stereo techniques, all drawing the same scene into the same images, so that each
//! can be profiled against the others (the modes Unity names multi-camera, multi-pass,
//! single-pass, single-pass instanced and multiview).

use serde::Serialize;

/// A stereo technique: how much of the work is done per eye.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash, Serialize)]
#[cfg_attr(feature = "cli", derive(clap::ValueEnum))]
#[serde(rename_all = "kebab-case")]
pub enum StereoMode {
    /// A full cull and render per eye: each eye culls against its own frustum and draws
    /// every visible instance with its own draw call, in its own pass.
    MultiCamera,
    /// One shared cull against the display frustum, then one pass per eye with a draw
    /// call per visible instance.
    MultiPass,
    /// One shared cull and one pass into the double-wide target; per visible instance one
    /// draw per eye, switching eye (viewport and eye binding) in the left, right, right,
    /// left cadence to halve the switches.
    SinglePass,
    /// The GPU-driven path: per display one multi-draw-indirect call with doubled
    /// instance counts (`instance >> 1` the object, `instance & 1` the eye).
    #[default]
    Instanced,
    /// `MULTIVIEW` into a two-layer target: the same culling with one view per instance
    /// (counts not doubled), the hardware repeating each draw per layer.
    Multiview,
}

impl StereoMode {
    /// Every mode, classic first.
    pub const ALL: [StereoMode; 5] = [
        StereoMode::MultiCamera,
        StereoMode::MultiPass,
        StereoMode::SinglePass,
        StereoMode::Instanced,
        StereoMode::Multiview,
    ];

    /// Draws recorded one per instance from a CPU cull (so culling is on the CPU).
    pub fn per_instance(self) -> bool {
        matches!(
            self,
            StereoMode::MultiCamera | StereoMode::MultiPass | StereoMode::SinglePass
        )
    }

    /// Culls each eye of a stereo display against its own frustum (not the display's).
    pub fn culls_per_eye(self) -> bool {
        self == StereoMode::MultiCamera
    }

    /// The mode as the CLI spells it.
    pub fn name(self) -> &'static str {
        match self {
            StereoMode::MultiCamera => "multi-camera",
            StereoMode::MultiPass => "multi-pass",
            StereoMode::SinglePass => "single-pass",
            StereoMode::Instanced => "instanced",
            StereoMode::Multiview => "multiview",
        }
    }
}
