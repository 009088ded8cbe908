//! A frame's input as data: everything a node needs to draw frame N as every other node
//! of a cluster draws it (the frame number, the time, the viewer's pose and gaze, and
//! the live scene's edits in order), and the identity of the scene those edits apply
//! to. An engine sends the bytes over its own transport; a node that applies the same
//! inputs to the same scene draws the same pixels as one process.
//!
//! The bytes ([`FrameInput::to_bytes`]): the magic `SCFI`, the version
//! ([`FRAME_INPUT_VERSION`], u16 little-endian), the payload's length (u32
//! little-endian), then the payload in `postcard`'s compact form. A message cut short,
//! of another version or damaged is an error, never a frame.

use glam::{Affine3A, Vec4};
use serde::{Deserialize, Serialize};

use crate::error::{Error, Result};
use crate::live::{Handle, LiveScene};
use crate::rig::{Gaze, Rig, Viewer};
use crate::scene::Instance;

/// The byte form's version: a node refuses any other.
pub const FRAME_INPUT_VERSION: u16 = 1;

const MAGIC: [u8; 4] = *b"SCFI";
const HEADER: usize = 4 + 2 + 4;

/// One frame's input.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct FrameInput {
    /// The frame's number, from 0.
    pub frame: u64,
    /// Seconds on the head's clock: what animations are posed at.
    pub time: f32,
    /// The tracked viewer.
    pub viewer: Viewer,
    /// Where the eyes look, for a rig with foveated displays.
    pub gaze: Option<Gaze>,
    /// The live scene's edits since the last frame, in the order they were made.
    pub edits: Vec<SceneEdit>,
}

/// One edit of a [`LiveScene`], as its head made it.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub enum SceneEdit {
    /// An instance inserted, and the handle the head's scene gave it: a replica that
    /// gives another has diverged ([`FrameInput::apply`] says so).
    Insert {
        /// The head's handle.
        handle: Handle,
        /// The instance.
        instance: Instance,
    },
    /// An instance moved ([`LiveScene::set_transform`]).
    Transform {
        /// Which.
        handle: Handle,
        /// Its new transform.
        world_from_local: Affine3A,
    },
    /// An instance recolored ([`LiveScene::set_color`]).
    Color {
        /// Which.
        handle: Handle,
        /// Its linear RGBA.
        color: Vec4,
    },
    /// An instance's own material changed ([`LiveScene::set_material`]).
    Material {
        /// Which.
        handle: Handle,
        /// The material, or its mesh's.
        material: Option<u32>,
    },
    /// An instance removed.
    Remove(Handle),
}

impl FrameInput {
    /// Applies the edits to `scene` in order, then the pose and gaze to `rig`.
    pub fn apply(&self, scene: &mut LiveScene, rig: &mut Rig) -> Result<()> {
        for edit in &self.edits {
            edit.apply(scene)?;
        }
        self.apply_pose(rig)
    }

    /// Applies the pose and gaze alone to `rig` (a scene that does not change).
    pub fn apply_pose(&self, rig: &mut Rig) -> Result<()> {
        rig.viewer = self.viewer;
        if let Some(gaze) = self.gaze {
            rig.set_gaze(gaze)
                .map_err(|message| Error::rig("frame input", &message))?;
        }
        Ok(())
    }

    /// The byte form: header, then the payload.
    pub fn to_bytes(&self) -> Vec<u8> {
        // A derived Serialize of plain data into memory cannot fail.
        let payload = postcard::to_stdvec(self).unwrap_or_default();
        let mut bytes = Vec::with_capacity(HEADER + payload.len());
        bytes.extend(MAGIC);
        bytes.extend(FRAME_INPUT_VERSION.to_le_bytes());
        bytes.extend((payload.len() as u32).to_le_bytes());
        bytes.extend(payload);
        bytes
    }

    /// The input `bytes` hold: an error naming what is wrong when they are cut short,
    /// of another version, or not a frame input.
    pub fn from_bytes(bytes: &[u8]) -> Result<FrameInput> {
        let invalid = |message: String| Error::FrameInput(message);
        if bytes.len() < HEADER {
            return Err(invalid(format!(
                "{} bytes, shorter than the {HEADER}-byte header",
                bytes.len()
            )));
        }
        if bytes[..4] != MAGIC {
            return Err(invalid("not a frame input (no SCFI magic)".into()));
        }
        let version = u16::from_le_bytes([bytes[4], bytes[5]]);
        if version != FRAME_INPUT_VERSION {
            return Err(invalid(format!(
                "version {version}, this build reads version {FRAME_INPUT_VERSION}"
            )));
        }
        let length = u32::from_le_bytes([bytes[6], bytes[7], bytes[8], bytes[9]]) as usize;
        let payload = &bytes[HEADER..];
        if payload.len() != length {
            return Err(invalid(format!(
                "the payload is {} bytes, its header says {length}",
                payload.len()
            )));
        }
        postcard::from_bytes(payload).map_err(|e| invalid(format!("damaged payload: {e}")))
    }
}

impl SceneEdit {
    /// Makes the edit in `scene`.
    pub fn apply(&self, scene: &mut LiveScene) -> Result<()> {
        match *self {
            SceneEdit::Insert { handle, instance } => {
                let given = scene.insert(instance)?;
                if given != handle {
                    return Err(Error::BadHandle(format!(
                        "an insert was given {given:?} here, {handle:?} by the head: the scenes have diverged"
                    )));
                }
            }
            SceneEdit::Transform {
                handle,
                world_from_local,
            } => scene.set_transform(handle, world_from_local)?,
            SceneEdit::Color { handle, color } => scene.set_color(handle, color)?,
            SceneEdit::Material { handle, material } => scene.set_material(handle, material)?,
            SceneEdit::Remove(handle) => {
                scene.remove(handle)?;
            }
        }
        Ok(())
    }
}

/// What a node loaded, as a hash every node can compare at start: BLAKE3 of the scene
/// spec and, when the spec names a file, of the file's bytes (a `.gltf`'s external
/// buffers and images are not read).
pub fn scene_identity(spec: &str) -> Result<[u8; 32]> {
    let mut hasher = blake3::Hasher::new();
    hasher.update(spec.as_bytes());
    let path = std::path::Path::new(spec);
    if path.is_file() {
        let bytes = std::fs::read(path).map_err(|e| Error::Scene {
            path: path.to_path_buf(),
            message: e.to_string(),
        })?;
        hasher.update(&bytes);
    }
    Ok(*hasher.finalize().as_bytes())
}
