//! A live scene's punctual lights by handle: each in a slot of `Scene::lights` with a
//! generation, lit or removed; a change sends the lit ones up whole at the next sync.

use super::LiveScene;
use crate::error::{Error, Result};

/// A stable reference to one punctual light of a [`LiveScene`].
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct LightHandle {
    slot: u32,
    generation: u32,
}

impl LiveScene {
    /// The handles of the lights the scene started with, in order.
    pub fn light_handles(&self) -> Vec<LightHandle> {
        (self.light_slots.iter().enumerate())
            .filter(|(_, (_, lit))| *lit)
            .map(|(slot, &(generation, _))| LightHandle {
                slot: slot as u32,
                generation,
            })
            .collect()
    }

    /// The lights lit now, as the renderer shades them.
    pub fn lights(&self) -> Vec<crate::lights::Light> {
        (self.scene.lights.iter().zip(&self.light_slots))
            .filter(|(_, (_, lit))| *lit)
            .map(|(l, _)| *l)
            .collect()
    }

    /// Adds `light` (checked: [`crate::lights::Light::check`]) in a new slot; an error
    /// past [`crate::lights::MAX_LIGHTS`] lit lights.
    pub fn insert_light(&mut self, light: crate::lights::Light) -> Result<LightHandle> {
        light.check().map_err(Error::InvalidScene)?;
        let lit = self.light_slots.iter().filter(|(_, lit)| *lit).count();
        if lit >= crate::lights::MAX_LIGHTS {
            return Err(Error::InvalidScene(format!(
                "a light past the budget of {} (lights::MAX_LIGHTS)",
                crate::lights::MAX_LIGHTS
            )));
        }
        self.scene.lights.push(light);
        self.light_slots.push((0, true));
        self.changes.lights = true;
        Ok(LightHandle {
            slot: self.light_slots.len() as u32 - 1,
            generation: 0,
        })
    }

    /// Replaces the light behind `handle` (moved, recolored, re-aimed).
    pub fn set_light(&mut self, handle: LightHandle, light: crate::lights::Light) -> Result<()> {
        self.check_light(handle)?;
        light.check().map_err(Error::InvalidScene)?;
        self.scene.lights[handle.slot as usize] = light;
        self.changes.lights = true;
        Ok(())
    }

    /// Turns the light behind `handle` off for good; `handle` is then an error.
    pub fn remove_light(&mut self, handle: LightHandle) -> Result<crate::lights::Light> {
        self.check_light(handle)?;
        let slot = &mut self.light_slots[handle.slot as usize];
        *slot = (slot.0.wrapping_add(1), false);
        self.changes.lights = true;
        Ok(self.scene.lights[handle.slot as usize])
    }

    fn check_light(&self, handle: LightHandle) -> Result<()> {
        match self.light_slots.get(handle.slot as usize) {
            Some(&(generation, true)) if generation == handle.generation => Ok(()),
            _ => Err(Error::BadHandle(format!(
                "light {handle:?} was removed or never given"
            ))),
        }
    }
}
