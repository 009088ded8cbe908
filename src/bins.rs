//! Material bins: the draws that can share one multi-draw call, because they share a
//! pipeline. The cull writes each bin's draws into its own fixed range of the indirect
//! buffer (bin, then level, then mesh) and its count into its own word, so a display's
//! draw pass sets each bin's pipeline once and issues one multi-draw for it: draw calls
//! per display are the scene's bins, whatever the instance count.
//!
//! A mesh's bin is its material's [`Bin`]: the alpha mode's pipeline state and the
//! shading function. Bins are drawn in [`Bin`] order: by [`BinKind`] first, so blended
//! surfaces come last, over everything that writes depth.

use crate::error::{Error, Result};
use crate::scene::{AlphaMode, Instance, Material, Mesh, Scene, SecondUv, Shading};

/// The pipeline state a bin's draws need, in drawing order.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum BinKind {
    /// Writes depth, never discards: the pipeline keeps early depth testing.
    #[default]
    Opaque,
    /// Discards below the material's cutoff (alpha to coverage under MSAA).
    Mask,
    /// Blended by alpha over what is drawn, without writing depth.
    Blend,
}

impl BinKind {
    /// Every kind, in drawing order.
    pub const ALL: [BinKind; 3] = [BinKind::Opaque, BinKind::Mask, BinKind::Blend];

    /// The kind a material of `alpha` is drawn with.
    pub fn of(alpha: AlphaMode) -> BinKind {
        match alpha {
            AlphaMode::Opaque => BinKind::Opaque,
            AlphaMode::Mask { .. } => BinKind::Mask,
            AlphaMode::Blend => BinKind::Blend,
        }
    }

    /// Its value in WGSL (`ALPHA_MODE`).
    pub fn wgsl(self) -> u32 {
        self as u32
    }
}

/// What a bin's draws share: one pipeline.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct Bin {
    /// The alpha mode's pipeline state (first: it orders the bins).
    pub alpha: BinKind,
    /// Its materials read two sets of texture coordinates ([`Material::second_uv`]):
    /// its pipeline passes the second to the fragment stage. Apart from the others
    /// because a varying more is not free: lavapipe's multiview misroutes clipped
    /// triangles as varyings grow, and a software rasterizer sets up every varying of
    /// every triangle.
    pub second_uv: bool,
    /// The shading function.
    pub shading: Shading,
}

/// The most bins a scene may have (and words its counts buffer keeps for them).
pub const MAX_BINS: usize = 64;

/// A scene's bins: the ones its meshes need, in drawing order, and each mesh's bin.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Bins {
    /// Ascending; at least one (an empty scene has one opaque, lit bin).
    pub kinds: Vec<Bin>,
    /// Per mesh, its index into `kinds`.
    pub of_mesh: Vec<u32>,
}

/// One bin's entries of a draws buffer.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct BinRange {
    /// The pipeline its draws need.
    pub kind: Bin,
    /// Its first entry.
    pub first: u32,
    /// Its entries: its meshes times the levels of detail; for a blended bin, one per
    /// place of its meshes (each visible blended instance is its own draw, in sorted
    /// order).
    pub capacity: u32,
}

impl Bin {
    /// The bin of a material (`None`: a scene without materials draws lit and opaque).
    pub fn of(material: Option<&Material>) -> Bin {
        material.map_or(Bin::default(), |m| Bin {
            alpha: BinKind::of(m.alpha),
            second_uv: m.second_uv != SecondUv::default(),
            shading: m.shading,
        })
    }
}

impl Bins {
    /// The bins of `scene`'s meshes, each by its material ([`mesh_material`]).
    pub fn of(scene: &Scene) -> Bins {
        let kind_of = |m: usize| Bin::of(scene.materials.get(mesh_material(scene, m) as usize));
        let mesh_kinds: Vec<Bin> = (0..scene.meshes.len()).map(kind_of).collect();
        let mut kinds = mesh_kinds.clone();
        kinds.sort();
        kinds.dedup();
        if kinds.is_empty() {
            kinds.push(Bin::default());
        }
        let of_mesh = (mesh_kinds.iter())
            .map(|k| kinds.iter().position(|x| x == k).unwrap_or(0) as u32)
            .collect();
        Bins { kinds, of_mesh }
    }

    /// The index of the first blended bin (all later ones are blended too), or
    /// `u32::MAX` without one. Occlusion culling never marks their instances drawn:
    /// they are always drawn in the late phase, after every opaque surface, and are
    /// never occluders.
    pub fn first_blend_bin(&self) -> u32 {
        let blend = self.kinds.iter().position(|k| k.alpha == BinKind::Blend);
        blend.map_or(u32::MAX, |b| b as u32)
    }
}

/// Mesh `m`'s material: its first triangle's first vertex's (material 0 for a mesh
/// without triangles or whose indices lie outside the vertices; the renderer rejects
/// those and meshes that mix materials, `materials::records`).
pub fn mesh_material(scene: &Scene, m: usize) -> u32 {
    let mesh = &scene.meshes[m];
    if mesh.index_count == 0 {
        return 0;
    }
    let first = scene.indices.get(mesh.first_index as usize);
    first
        .and_then(|&i| vertex_material(scene, mesh, i))
        .unwrap_or(0)
}

/// The material of `mesh`'s vertex at `index` (an entry of its index list), if that
/// vertex exists.
pub fn vertex_material(scene: &Scene, mesh: &Mesh, index: u32) -> Option<u32> {
    let v = usize::try_from(index as i64 + mesh.base_vertex as i64).ok()?;
    scene.vertices.get(v).map(|v| v.material)
}

/// An instance's own material ([`Instance::material`]) must exist and keep its mesh's
/// bin: the cull groups draws by mesh, so the instance is drawn by its mesh's pipeline.
pub fn check_override(scene: &Scene, instance: &Instance) -> Result<()> {
    let Some(own) = instance.material else {
        return Ok(());
    };
    let Some(material) = scene.materials.get(own as usize) else {
        return Err(Error::InvalidScene(format!(
            "an instance names material {own} of {}",
            scene.materials.len()
        )));
    };
    let Some(mesh) = scene.meshes.get(instance.mesh as usize) else {
        return Ok(());
    };
    let mesh_bin = Bin::of(
        scene
            .materials
            .get(mesh_material(scene, instance.mesh as usize) as usize),
    );
    match Bin::of(Some(material)) == mesh_bin {
        true => Ok(()),
        false => Err(Error::InvalidScene(format!(
            "an instance of mesh {:?} names material {own} ({:?}), drawn as {:?}; its mesh is drawn as {:?}, and an instance keeps its mesh's pipeline",
            mesh.name,
            material.name,
            Bin::of(Some(material)),
            mesh_bin
        ))),
    }
}
