//! Scenes by name, above the importers: `default` (the built-in room),
//! `procedural:N[:MESHES[:SEED[:textured][:glassP]]]`, `city:N[:SEED]`, `rooms:N[:SEED]`, `crowd:N[:SEED]`, or a
//! `.gltf` / `.glb` file.

use std::path::Path;

use crate::error::{Error, Result};
use crate::scene::Scene;
use crate::{gltf_import, procedural};

/// The scene spec naming the built-in room (`assets/room.glb`).
pub const DEFAULT_SCENE: &str = "default";
/// Meshes a `procedural:N` scene uses when no count is given.
pub const DEFAULT_PROCEDURAL_MESHES: u32 = 8;
/// Seed a `procedural:N` scene uses when none is given.
pub const DEFAULT_PROCEDURAL_SEED: u64 = 1;
/// The built-in room (a furnished room at real scale, objects from an arm's length to
/// ten meters away), embedded so that `--scene default` works from any directory. Its
/// authoring code lives with the tests (`tests/support/room.rs`), which check that this
/// file is what it writes.
pub const ROOM_GLB: &[u8] = include_bytes!("../assets/room.glb");

/// `default` (the built-in room), `procedural:N[:MESHES[:SEED[:textured][:glassP]]]`
/// (`textured`: every mesh samples one generated base color texture; `glassP`: P % of
/// the meshes are blended glass, [`procedural::glaze`]), or a path to a `.gltf` / `.glb`
/// file.
/// An empty scene is an error: there would be nothing to cull or draw, and GPU
/// buffers cannot be empty.
pub fn load(spec: &str) -> Result<Scene> {
    if let Some(rest) = spec.strip_prefix("city:") {
        return checked(spec, parse_city(spec, rest)?);
    }
    if let Some(rest) = spec.strip_prefix("rooms:") {
        return checked(spec, parse_rooms(spec, rest)?);
    }
    if let Some(rest) = spec.strip_prefix("crowd:") {
        return checked(spec, parse_crowd(spec, rest)?);
    }
    let scene = match spec.strip_prefix("procedural:") {
        Some(rest) => {
            let (n, meshes, seed, (textured, glass)) = parse_procedural(spec, rest)?;
            let mut scene = procedural::scene(n, meshes, seed);
            if textured {
                procedural::texture(&mut scene);
            }
            procedural::glaze(&mut scene, glass);
            scene
        }
        None if spec == DEFAULT_SCENE => {
            gltf_import::import_bytes(ROOM_GLB, None, Path::new("assets/room.glb"))?
        }
        None => gltf_import::import(Path::new(spec))?,
    };
    checked(spec, scene)
}

/// Whether `spec` names a .gltf / .glb file (not the built-in room): a scene someone
/// else placed, which the CLI frames by its cameras or bounds.
pub fn is_file(spec: &str) -> bool {
    let lower = spec.to_lowercase();
    spec != DEFAULT_SCENE && (lower.ends_with(".gltf") || lower.ends_with(".glb"))
}

/// `scene` with non-finite instances dropped; an error when none remain.
fn checked(spec: &str, mut scene: Scene) -> Result<Scene> {
    let dropped = scene.drop_non_finite_instances();
    if dropped > 0 {
        log::warn!("{spec}: dropped {dropped} instance(s) with non-finite transforms");
    }
    if scene.instances.is_empty() {
        return Err(Error::SceneSpec {
            spec: spec.into(),
            message: "the scene has no mesh instances to draw".into(),
        });
    }
    Ok(scene)
}

/// `city:N[:SEED]`: [`procedural::city`].
fn parse_city(spec: &str, rest: &str) -> Result<Scene> {
    let mut fields = Fields::new(spec, rest, "city:N[:SEED]");
    let n = fields.count()?;
    let seed = fields.seed()?;
    fields.end()?;
    Ok(procedural::city(n, seed))
}

/// `rooms:N[:SEED]`: [`procedural::rooms`].
fn parse_rooms(spec: &str, rest: &str) -> Result<Scene> {
    let mut fields = Fields::new(spec, rest, "rooms:N[:SEED]");
    let n = fields.count()?;
    let seed = fields.seed()?;
    fields.end()?;
    Ok(procedural::rooms(n, seed))
}

/// `crowd:N[:SEED]`: [`crate::crowd::scene`].
fn parse_crowd(spec: &str, rest: &str) -> Result<Scene> {
    let mut fields = Fields::new(spec, rest, "crowd:N[:SEED]");
    let n = fields.count()?;
    let seed = fields.seed()?;
    fields.end()?;
    Ok(crate::crowd::scene(n, seed))
}

fn parse_procedural(spec: &str, rest: &str) -> Result<(u32, u32, u64, (bool, f64))> {
    let mut fields = Fields::new(spec, rest, PROCEDURAL_FORM);
    let n = fields.count()?;
    let meshes = match fields.parts.next() {
        Some(s) => s
            .parse()
            .ok()
            .filter(|&m: &u32| m > 0)
            .ok_or_else(|| fields.fail("MESHES is not a positive count"))?,
        None => DEFAULT_PROCEDURAL_MESHES,
    };
    let seed = fields.seed()?;
    let mut textured = false;
    let mut glass = 0.0;
    for part in fields.parts.by_ref() {
        let percent = part.strip_prefix("glass").map(str::parse::<f64>);
        match (part, percent) {
            ("textured", _) => textured = true,
            (_, Some(Ok(p))) if (0.0..=100.0).contains(&p) => glass = p,
            _ => {
                return Err(fields.fail(
                    "fields after SEED are `textured` or `glassP` (P % of the meshes, 0 to 100)",
                ));
            }
        }
    }
    fields.end()?;
    Ok((n, meshes, seed, (textured, glass)))
}

const PROCEDURAL_FORM: &str = "procedural:N[:MESHES[:SEED[:textured][:glassP]]]";

/// The `:`-separated fields of a generated scene's spec, read in order; errors name
/// the spec and the form it should have.
struct Fields<'a> {
    spec: &'a str,
    form: &'static str,
    parts: std::str::Split<'a, char>,
}

impl<'a> Fields<'a> {
    fn new(spec: &'a str, rest: &'a str, form: &'static str) -> Fields<'a> {
        Fields {
            spec,
            form,
            parts: rest.split(':'),
        }
    }

    fn fail(&self, message: &str) -> Error {
        Error::SceneSpec {
            spec: self.spec.into(),
            message: format!("{message}; expected {}", self.form),
        }
    }

    /// N, the instance count.
    fn count(&mut self) -> Result<u32> {
        let n = self.parts.next().and_then(|s| s.parse().ok());
        n.ok_or_else(|| self.fail("N is not a count"))
    }

    /// SEED, or the default seed when the spec ends here.
    fn seed(&mut self) -> Result<u64> {
        match self.parts.next() {
            Some(s) => s.parse().map_err(|_| self.fail("SEED is not an integer")),
            None => Ok(DEFAULT_PROCEDURAL_SEED),
        }
    }

    fn end(mut self) -> Result<()> {
        match self.parts.next() {
            Some(_) => Err(self.fail("too many fields")),
            None => Ok(()),
        }
    }
}
