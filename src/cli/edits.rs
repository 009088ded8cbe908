//! `--moving P --churn P`: seeded per-frame edits of a live scene, the same on every run,
//! for `stress`, `profile` and `cull`.

use clap::Args;
use glam::{Affine3A, Vec3};
use rand::seq::SliceRandom;
use rand::{Rng, SeedableRng};
use rand_pcg::Pcg64Mcg;

use crate::error::{Error, Result};
use crate::frame_input::SceneEdit;
use crate::live::{Handle, LiveScene};
use crate::renderer::PosingMode;
use crate::scene::Scene;

/// The live copy of `scene` a run of frames changes on the CPU, with its edit driver:
/// when `edits` asks for edits, or the scene's animations are posed on the CPU
/// (`posing`); `None` when nothing changes on the CPU (posed on the GPU, only the time
/// changes).
pub fn live_copy(
    scene: &Scene,
    edits: &EditArgs,
    posing: PosingMode,
) -> Result<Option<(LiveScene, EditDriver)>> {
    let cpu_posed = posing == PosingMode::Cpu && scene.is_animated();
    if !(edits.any() || cpu_posed) {
        return Ok(None);
    }
    let live = LiveScene::new(scene.clone());
    let driver = EditDriver::new(&live, edits)?;
    Ok(Some((live, driver)))
}

#[derive(Args, Clone, Copy, Debug, Default)]
pub struct EditArgs {
    /// Percent of instances whose transform changes every frame.
    #[arg(long, default_value_t = 0.0)]
    pub moving: f64,
    /// Percent of instances removed and inserted again every frame.
    #[arg(long, default_value_t = 0.0)]
    pub churn: f64,
}

impl EditArgs {
    pub fn any(&self) -> bool {
        self.moving > 0.0 || self.churn > 0.0
    }

    fn check(&self) -> Result<()> {
        for (name, p) in [("--moving", self.moving), ("--churn", self.churn)] {
            if !(0.0..=100.0).contains(&p) {
                return Err(Error::Unsupported(format!(
                    "{name} {p}: a percentage from 0 to 100"
                )));
            }
        }
        Ok(())
    }
}

/// Drives the edits: a fixed subset moves on small circles around where it started, and
/// a random subset (from a seeded generator) is removed and inserted again each frame.
pub struct EditDriver {
    handles: Vec<Handle>,
    /// Indices into `handles` of the instances that move, with their first transform.
    moving: Vec<(usize, Affine3A)>,
    churn: usize,
    rng: Pcg64Mcg,
}

impl EditDriver {
    pub fn new(live: &LiveScene, args: &EditArgs) -> Result<EditDriver> {
        args.check()?;
        let handles = live.handles();
        let mut rng = Pcg64Mcg::seed_from_u64(0x5eed);
        let mut order: Vec<usize> = (0..handles.len()).collect();
        order.shuffle(&mut rng);
        let share = |p: f64| (handles.len() as f64 * p / 100.0).round() as usize;
        let moving = order[..share(args.moving)]
            .iter()
            .map(|&i| Ok((i, live.get(handles[i])?.world_from_local)))
            .collect::<Result<_>>()?;
        Ok(EditDriver {
            churn: share(args.churn),
            handles,
            moving,
            rng,
        })
    }

    /// Frame `frame`'s edits: the movers step along their circles (radius 0.2 m, one turn
    /// in about six seconds at 90 fps), then the churned instances go and come back.
    /// Returns them in order, as a cluster's head sends them.
    pub fn apply(&mut self, live: &mut LiveScene, frame: u32) -> Result<Vec<SceneEdit>> {
        let mut edits = Vec::with_capacity(self.moving.len() + 2 * self.churn);
        for (k, &(i, start)) in self.moving.iter().enumerate() {
            let phase = frame as f32 * 0.012 + k as f32;
            let offset = 0.2 * Vec3::new(phase.cos() - 1.0, 0.0, phase.sin());
            let moved = Affine3A::from_translation(offset) * start;
            live.set_transform(self.handles[i], moved)?;
            edits.push(SceneEdit::Transform {
                handle: self.handles[i],
                world_from_local: moved,
            });
        }
        for _ in 0..self.churn {
            let i = self.rng.random_range(0..self.handles.len());
            let instance = live.remove(self.handles[i])?;
            edits.push(SceneEdit::Remove(self.handles[i]));
            self.handles[i] = live.insert(instance)?;
            edits.push(SceneEdit::Insert {
                handle: self.handles[i],
                instance,
            });
        }
        Ok(edits)
    }
}
