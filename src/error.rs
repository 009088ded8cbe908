//! Typed errors. Every fallible public function returns [`Error`]; the CLI prints its
//! `Display` as one line and exits non-zero.

use std::path::PathBuf;

/// Installs the software Vulkan driver on a GPU-less Debian or Ubuntu machine.
pub const LAVAPIPE_INSTALL: &str = "apt-get install -y mesa-vulkan-drivers";

/// Everything the library can fail with, each naming what failed and, where it helps,
/// what to do.
#[derive(Debug, thiserror::Error)]
pub enum Error {
    /// No adapter on any enabled backend: usually no Vulkan driver is installed.
    #[error(
        "no GPU adapter found (backends {backends}): install a Vulkan driver; on a GPU-less Debian or Ubuntu machine run `{LAVAPIPE_INSTALL}` (lavapipe)"
    )]
    NoAdapter {
        /// The backends searched.
        backends: String,
    },

    /// `WGPU_ADAPTER_NAME` is set but names none of the adapters present.
    #[error("WGPU_ADAPTER_NAME={wanted:?} matches no adapter; present: {present}")]
    AdapterNotFound {
        /// The variable's value.
        wanted: String,
        /// The adapters present, by name.
        present: String,
    },

    /// The adapter refused the device we asked for.
    #[error("the adapter refused the device: {0}")]
    RequestDevice(#[from] wgpu::RequestDeviceError),

    /// A rig (preset, file or override) is invalid.
    #[error("rig {origin}: {message}")]
    Rig {
        /// The preset, file or step that failed (`prepare`, a display's name).
        origin: String,
        /// What is wrong, with the field.
        message: String,
    },

    /// A scene file could not be read or makes no sense.
    #[error("scene {path}: {message}")]
    Scene {
        /// The scene file.
        path: PathBuf,
        /// What is wrong, naming the part of the file.
        message: String,
    },

    /// A scene's parts do not fit together (e.g. a vertex naming a material the scene
    /// lacks).
    #[error("scene: {0}")]
    InvalidScene(String),

    /// A material's shading function (WGSL, `RendererOptions::material` or `hooks`)
    /// does not compile.
    #[error("material {material:?}: its shading function does not compile{}: {message}", at_line(.line))]
    Shading {
        /// The first material that uses the function.
        material: String,
        /// The line of the function at fault, when the fault lies in it.
        line: Option<usize>,
        /// The compiler's message.
        message: String,
    },

    /// A handle to an instance that was removed, or that this scene never issued.
    #[error("bad handle: {0}")]
    BadHandle(String),

    /// An edit with a NaN or infinite value; nothing was changed.
    #[error("{0} is not finite (NaN or infinite); nothing was changed")]
    NonFinite(String),

    /// A `procedural:N[:M]` scene specification is malformed.
    #[error("scene {spec:?}: {message}")]
    SceneSpec {
        /// The specification as given.
        spec: String,
        /// What is wrong with it.
        message: String,
    },

    /// The device or the chosen mode cannot do what was asked.
    #[error("{0}")]
    Unsupported(String),

    /// The scene or rig does not fit the device's limits.
    #[error("{0}")]
    Limits(String),

    /// A display draws material bins of a pipeline of the caller's own that it was not
    /// given (`Renderer::set_own_pipeline`).
    #[error(
        "display {index} draws materials of Shading::Own({shading}) and has no pipeline for them: give it one with Renderer::set_own_pipeline({index}, {shading}, ..)"
    )]
    MissingOwnPipeline {
        /// The display.
        index: usize,
        /// The `Shading::Own` index.
        shading: u32,
    },
    /// A display index past the renderer's displays.
    #[error("display {index} does not exist: the renderer has {displays} displays")]
    NoSuchDisplay {
        /// The index asked for.
        index: usize,
        /// The renderer's displays.
        displays: usize,
    },

    /// `encode` was given a different number of targets than the renderer has displays.
    #[error("{targets} targets for {displays} displays: pass one target per display")]
    TargetCount {
        /// The targets given.
        targets: usize,
        /// The renderer's displays.
        displays: usize,
    },

    /// With occlusion, a display's depth target cannot be read into its pyramids.
    #[error(
        "display {display}: occlusion reads the depth target, whose texture lacks TEXTURE_BINDING (make it with that usage, or turn occlusion off)"
    )]
    DepthNotBindable {
        /// The display's index.
        display: usize,
    },

    /// Reading results back from the GPU failed (device lost, map failure).
    #[error("GPU readback failed: {0}")]
    Readback(String),

    /// A frame's input in bytes ([`crate::frame_input::FrameInput::from_bytes`]) is not
    /// one: cut short, of another version, or damaged.
    #[error("frame input: {0}")]
    FrameInput(String),

    /// The device was lost (driver reset, removal, or destroyed).
    #[error("the GPU device was lost: {0}")]
    DeviceLost(String),

    /// wgpu reported a validation or out-of-memory error inside an error scope.
    #[error("wgpu: {0}")]
    Wgpu(#[from] wgpu::Error),

    /// Writing an output file failed.
    #[error("{path}: {source}")]
    Io {
        /// The file.
        path: PathBuf,
        /// Why.
        source: std::io::Error,
    },

    /// Two images that should compare have different sizes.
    #[error("{0}: only images of one size compare")]
    ImageSizes(String),

    /// Reading or writing an image failed.
    #[error("{path}: {source}")]
    Image {
        /// The image file.
        path: PathBuf,
        /// Why.
        source: image::ImageError,
    },
}

impl Error {
    /// The message on one line: wgpu's errors span several ("Caused by: ...").
    pub fn one_line(&self) -> String {
        self.to_string()
            .lines()
            .map(str::trim)
            .filter(|l| !l.is_empty())
            .collect::<Vec<_>>()
            .join(" ")
    }

    pub(crate) fn rig(origin: impl Into<String>, message: impl Into<String>) -> Self {
        Error::Rig {
            origin: origin.into(),
            message: message.into(),
        }
    }

    pub(crate) fn io(path: impl Into<PathBuf>, source: std::io::Error) -> Self {
        Error::Io {
            path: path.into(),
            source,
        }
    }
}

/// The library's results.
pub type Result<T, E = Error> = std::result::Result<T, E>;

fn at_line(line: &Option<usize>) -> String {
    line.map_or(String::new(), |l| format!(" (its line {l})"))
}
