//! `render --motion-vectors on`: the previous frame drawn first (at the pose and time
//! the `--previous-*` flags give), then each display's motion written as raw vectors
//! and as a picture.

use std::path::Path;

use clap::Args;
use serde::Serialize;

use super::parse_vec3;
use super::session::Session;
use crate::error::{Error, Result};
use crate::readback::read_motion;

/// The frame the motion is measured from; each defaults to the frame's own.
#[derive(Args, Clone, Debug, Default)]
pub struct PreviousArgs {
    /// The previous frame's viewer position, x,y,z meters.
    #[arg(long, value_parser = parse_vec3, allow_hyphen_values = true)]
    pub previous_viewer: Option<[f32; 3]>,
    /// The previous frame's yaw in degrees.
    #[arg(long, allow_hyphen_values = true)]
    pub previous_yaw: Option<f32>,
    /// The previous frame's pitch in degrees.
    #[arg(long, allow_hyphen_values = true)]
    pub previous_pitch: Option<f32>,
    /// The previous frame's time in seconds.
    #[arg(long, allow_hyphen_values = true)]
    pub previous_time: Option<f32>,
}

impl PreviousArgs {
    /// Draws the previous frame (a frame at `time` with the session's pose where a flag
    /// gives nothing), so that the next frame measures its motion from it.
    pub fn draw(&self, session: &mut Session, time: f32) -> Result<()> {
        let current = session.rig.viewer;
        let viewer = &mut session.rig.viewer;
        viewer.position = self.previous_viewer.unwrap_or(viewer.position);
        viewer.yaw_deg = self.previous_yaw.unwrap_or(viewer.yaw_deg);
        viewer.pitch_deg = self.previous_pitch.unwrap_or(viewer.pitch_deg);
        let drawn = session.frame(self.previous_time.unwrap_or(time));
        session.rig.viewer = current;
        drawn?;
        session.gpu.wait()
    }
}

/// One display's motion as written.
#[derive(Serialize)]
pub struct MotionStats {
    /// Width x height x 2 little-endian f32 in pixels, current minus previous, rows
    /// from the top.
    pub file: String,
    /// The picture: red x, green y, 128 for no motion, full scale at `scale_px`.
    pub image: String,
    pub width: u32,
    pub height: u32,
    /// The largest component's magnitude, in pixels: the picture's full scale (1 at
    /// least).
    pub scale_px: f32,
}

/// Display `index`'s motion, read back, written as `<name>-motion.f32` and
/// `<name>-motion.png` under `out`.
pub fn write_motion(session: &Session, index: usize, out: &Path) -> Result<MotionStats> {
    let (device, queue) = (&session.gpu.device, &session.gpu.queue);
    let Some(texture) = &session.targets[index].motion else {
        return Err(Error::Unsupported(
            "motion vectors: the renderer was made without them".into(),
        ));
    };
    let values = read_motion(device, queue, texture)?;
    let name = &session.rig.displays[index].name;
    let file = out.join(format!("{name}-motion.f32"));
    let bytes: Vec<u8> = values
        .iter()
        .flatten()
        .flat_map(|v| v.to_le_bytes())
        .collect();
    std::fs::write(&file, bytes).map_err(|e| Error::io(&file, e))?;
    let scale = (values.iter().flatten()).fold(1.0f32, |m, v| m.max(v.abs()));
    let (width, height) = (texture.width(), texture.height());
    let level = |v: f32| (128.0 + 127.0 * v / scale).round() as u8;
    let picture = image::RgbaImage::from_fn(width, height, |x, y| {
        let [mx, my] = values[(y * width + x) as usize];
        image::Rgba([level(mx), level(my), 128, 255])
    });
    let image = out.join(format!("{name}-motion.png"));
    super::save(&picture, &image)?;
    Ok(MotionStats {
        file: file.display().to_string(),
        image: image.display().to_string(),
        width,
        height,
        scale_px: scale,
    })
}
