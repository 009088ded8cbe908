//! glTF morph targets into [`crate::morph`]: a node's morphed primitive gets a mesh
//! of its own (the morph pass writes its weighted vertices into it; the node's
//! instancing copies share it), its targets' `POSITION`, `NORMAL` and `TANGENT` offsets
//! become the pass's deltas, its weights come from the node (else the mesh, else zeros)
//! and from animations of the node's `weights`, and its culling sphere grows to hold
//! every pose those weights reach. A skinned primitive is morphed in its skin's rest
//! vertices, before the skinning pass.

use glam::Vec3;
use gltf::Semantic;

use super::{Importer, Step};
use crate::morph::{Morph, MorphDelta, MorphVertex, WeightChannel};
use crate::pose::{Channel, Interpolation, Property};
use crate::scene::Vertex;

/// A morph read while placing nodes, finished once the animations are read.
pub(super) struct PendingMorph {
    /// Index into the scene's morphs.
    morph: usize,
    /// The glTF node whose weights it takes.
    node: usize,
    /// Its own mesh (its bounds grow), or for a skinned one its skin's (whose joints'
    /// bounds grow instead: `reach` is kept for `resolve_skins`).
    mesh: u32,
    skinned: bool,
    /// Its vertices' range of the morphed vertices (and their deltas, `targets` each).
    vertices: std::ops::Range<usize>,
}

impl Importer<'_> {
    /// Adds the morph of `node`'s `primitive` (read as `vertices`) writing
    /// `destinations` in order (the scene's vertices, or with `skinned` the skin's
    /// rest vertices); `mesh` is the mesh it moves. Nothing without targets.
    pub(super) fn add_morph(
        &mut self,
        (node, primitive): (&gltf::Node, &gltf::Primitive),
        (vertices, destinations): (&[Vertex], std::ops::Range<u32>),
        (mesh, skinned): (u32, bool),
    ) -> Step<()> {
        let targets: Vec<_> = primitive.morph_targets().collect();
        if targets.is_empty() {
            return Ok(());
        }
        let where_ = format!("node {} primitive {}", node.index(), primitive.index());
        let count = vertices.len();
        let mut deltas = vec![MorphDelta::default(); count * targets.len()];
        for (t, target) in targets.iter().enumerate() {
            let attributes = [
                (Semantic::Positions, target.positions()),
                (Semantic::Normals, target.normals()),
                (Semantic::Tangents, target.tangents()),
            ];
            for (semantic, accessor) in attributes {
                let Some(accessor) = accessor else { continue };
                let what = format!("{where_} target {t} {semantic:?}");
                let offsets = self.floats::<3>(&accessor, &what)?;
                if offsets.len() != count {
                    return Err(format!(
                        "{what}: {} offsets for {count} vertices",
                        offsets.len()
                    ));
                }
                if let Some(bad) = offsets.iter().find(|o| !o.iter().all(|c| c.is_finite())) {
                    return Err(format!("{what}: {bad:?} is not finite"));
                }
                for (v, o) in offsets.into_iter().enumerate() {
                    let d = &mut deltas[v * targets.len() + t];
                    match semantic {
                        Semantic::Positions => d.position = o,
                        Semantic::Normals => d.normal = o,
                        _ => d.tangent = o,
                    }
                }
            }
        }
        let defaults = default_weights(node, targets.len(), &where_)?;
        let morphs = &mut self.scene.morphs;
        let first_weight = morphs.weights.len() as u32;
        let first_delta = morphs.deltas.len() as u32;
        let first_vertex = morphs.vertices.len();
        for (i, (v, destination)) in vertices.iter().zip(destinations).enumerate() {
            morphs.vertices.push(MorphVertex {
                position: v.position,
                normal: v.normal,
                tangent: v.tangent,
                first_delta: first_delta + (i * targets.len()) as u32,
                first_weight,
                targets: targets.len() as u32,
                destination,
                skinned: u32::from(skinned),
            });
        }
        morphs.deltas.extend(deltas);
        morphs.weights.extend(&defaults);
        morphs.morphs.push(Morph {
            mesh,
            defaults,
            channels: Vec::new(),
            first_weight,
        });
        self.pending_morphs.push(PendingMorph {
            morph: morphs.morphs.len() - 1,
            node: node.index(),
            mesh,
            skinned,
            vertices: first_vertex..morphs.vertices.len(),
        });
        Ok(())
    }

    /// A channel of `node`'s morph weights (`at` names it), four weights to a
    /// [`Channel`], kept with each morph of the node; `duration` is its animation's.
    pub(super) fn weight_channel(
        &mut self,
        channel: &gltf::animation::Channel,
        (at, duration): (&str, f32),
    ) -> Step<()> {
        let node = channel.target().node().index();
        let morphs: Vec<usize> = (self.pending_morphs.iter())
            .filter(|p| p.node == node)
            .map(|p| p.morph)
            .collect();
        let Some(&first) = morphs.first() else {
            return Ok(()); // no morphed primitive of this node is drawn
        };
        let targets = self.scene.morphs.morphs[first].defaults.len();
        let sampler = channel.sampler();
        let where_ = || at.to_owned();
        let times: Vec<f32> = self.read(sampler.input().index() as u64, &where_)?;
        let values: Vec<f32> = self.read(sampler.output().index() as u64, &where_)?;
        let interpolation = match sampler.interpolation() {
            gltf::animation::Interpolation::Step => Interpolation::Step,
            gltf::animation::Interpolation::Linear => Interpolation::Linear,
            gltf::animation::Interpolation::CubicSpline => Interpolation::CubicSpline,
        };
        let per_key = match interpolation {
            Interpolation::CubicSpline => 3 * targets,
            _ => targets,
        };
        if values.len() != per_key * times.len() {
            return Err(format!(
                "{at}: {} weights for {} keys of {targets} targets",
                values.len(),
                times.len()
            ));
        }
        for group in 0..targets.div_ceil(4) {
            let c = Channel {
                node: 0,
                property: Property::Translation,
                interpolation,
                times: times.clone(),
                values: (values.chunks_exact(targets))
                    .map(|key| {
                        let mut four = [0.0; 4];
                        for (f, w) in four.iter_mut().zip(key.iter().skip(4 * group)) {
                            *f = *w;
                        }
                        glam::Vec4::from(four)
                    })
                    .collect(),
            };
            c.check().map_err(|e| format!("{at}: {e}"))?;
            for &m in &morphs {
                self.scene.morphs.morphs[m].channels.push(WeightChannel {
                    group: group as u32,
                    duration,
                    channel: c.clone(),
                });
            }
        }
        Ok(())
    }

    /// Once the animations are read: each morphed mesh's sphere grows by its morph's
    /// reach ([`Morph::reach`]); returns, per skinned mesh, the reach its joints'
    /// bounds grow by.
    pub(super) fn finish_morphs(&mut self) -> Vec<(u32, f32)> {
        self.scene.morphs.set_time(0.0);
        let mut skinned = Vec::new();
        for p in std::mem::take(&mut self.pending_morphs) {
            let morphs = &self.scene.morphs;
            let targets = morphs.morphs[p.morph].defaults.len();
            let deltas = &morphs.deltas[p.vertices.start * targets..p.vertices.end * targets];
            let reach = morphs.morphs[p.morph].reach(deltas);
            match p.skinned {
                true => skinned.push((p.mesh, reach)),
                false => self.scene.meshes[p.mesh as usize].bounds.w += reach,
            }
        }
        skinned
    }
}

/// The node's `weights`, else its mesh's, else zeros: one per target.
fn default_weights(node: &gltf::Node, targets: usize, where_: &str) -> Step<Vec<f32>> {
    let given = node
        .weights()
        .or_else(|| node.mesh().and_then(|m| m.weights()));
    let weights = given.map_or_else(|| vec![0.0; targets], <[f32]>::to_vec);
    if weights.len() != targets {
        return Err(format!(
            "{where_}: {} weights for {targets} morph targets",
            weights.len()
        ));
    }
    match weights.iter().find(|w| !w.is_finite()) {
        Some(w) => Err(format!("{where_}: weight {w} is not finite")),
        None => Ok(weights),
    }
}

/// How much a bind-space sphere's radius grows for a mesh-space reach under the
/// inverse bind matrix `ib`: its largest axis.
pub(super) fn bind_stretch(ib: &glam::Affine3A) -> f32 {
    let m = ib.matrix3;
    [m.x_axis, m.y_axis, m.z_axis]
        .iter()
        .map(|a| Vec3::from(*a).length())
        .fold(0.0, f32::max)
}
