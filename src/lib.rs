//! stereocull: scene submission for stereo and multi-display rendering on wgpu.
//!
//! The work of a frame is split the way the chapter *Efficient Stereo and VR Rendering*
//! splits it: the **frame** (once per frame: the rig resolved into every eye, display
//! and frame frustum), the **display** context (once per display: culling against the
//! combined frustum of both eyes and building the multi-draw-indirect buffers), and the
//! **eye** context (only what truly differs per eye: the projection, and the eye
//! position for specular).
//!
//! Modules, in the order data flows: [`rig`] (viewer and displays, resolved once per
//! frame) -> [`frustum`] (eye, display and frame frusta, in f64) -> [`contexts`] (what
//! shaders read per display and eye) -> [`scene`] (what is drawn; filled by
//! [`gltf_import`] or [`procedural`], chosen by name in [`scene_spec`]; [`pose`] moves
//! its animated instances once per frame) -> [`records`]
//! (GPU layouts; [`places`], each instance's place in the cull order) -> [`cull`]
//! (visible lists and draw arguments, CPU or GPU) -> [`draw`]
//! (pipelines, passes, the one indirect call). [`renderer::Renderer`] ties them together
//! for embedders; [`shaders`] composes the WGSL and declares every binding once.
//!
//! An embedder needs what the crate root re-exports: a [`Scene`] (or a [`LiveScene`]
//! that changes), a [`Rig`], a [`Renderer`] made with [`RendererOptions`], and the calls
//! of [`renderer`]'s documentation in their order (`new`; each frame `sync`, `prepare`,
//! `encode` or `encode_culls` and `draw_display`; `diagnostics` to read a frame back).
//! The other modules are the parts, public for tests, benches and tools: the CPU
//! reference cull ([`cull::cpu`]) is the one to profile the GPU against.

#![warn(missing_docs)]

pub mod basisu;
pub mod bins;
pub mod buffers;
/// The `stereocull` binary's commands (feature `cli`): not part of the library's API.
#[cfg(feature = "cli")]
#[doc(hidden)]
pub mod cli;
/// The old path of [`foveated_composite`], kept for one release.
#[doc(hidden)]
pub use foveated_composite as composite;
pub mod compositor;
pub mod contexts;
pub mod crowd;
pub mod cull;
pub mod device;
pub mod draw;
pub mod error;
pub mod exposure;
pub mod far_layer;
pub mod foveated_composite;
pub mod frame_input;
pub mod frustum;
pub mod gltf_import;
pub mod keep;
pub mod ktx2_raw;
pub mod lights;
pub mod live;
pub mod materials;
pub mod morph;
pub mod motion;
pub mod occlusion;
pub mod pbr;
pub mod places;
pub mod pose;
pub mod pose_tables;
pub mod procedural;
pub mod profiling;
pub mod readback;
pub mod records;
pub mod renderer;
pub mod rig;
mod scatter;
pub mod scene;
pub mod scene_spec;
pub mod shaders;
pub mod shadow;
pub mod shapes;
pub mod skin;
mod sphere_projection;

pub use error::{Error, Result};
pub use live::LiveScene;
pub use renderer::{
    CullMode, Diagnostics, DisplayTarget, FramePlan, FrameStats, Renderer, RendererOptions,
    StereoMode, TargetViews,
};
pub use rig::Rig;
pub use scene::Scene;
