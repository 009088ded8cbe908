//! Which glTF extensions the importer reads, and what a file that uses others gets.
//!
//! glTF's rule: an extension in `extensionsUsed` alone may be ignored (the file still
//! draws, perhaps without what the extension adds); one in `extensionsRequired` may
//! not. So an unread extension the file only uses is reported ([`uses`], `info
//! --scene`) and warned once by the import, and only an unread required one is an
//! error, naming it (and, where one exists, the tool that writes the file without it).
//! The gltf crate refuses every required extension outside its own short list, so
//! [`check_required`] decides instead and then clears the list before the crate
//! validates.

use gltf::json;

use super::Step;

/// The extensions the importer reads.
pub const READ: &[&str] = &[
    "EXT_mesh_gpu_instancing",
    "EXT_meshopt_compression",
    "KHR_materials_emissive_strength",
    "KHR_lights_punctual",
    "KHR_materials_unlit",
    "KHR_mesh_quantization",
    "KHR_texture_basisu",
    "KHR_texture_transform",
];

/// How a file that requires an extension we do not read can be made readable.
const REMEDIES: &[(&str, &str)] = &[(
    "KHR_draco_mesh_compression",
    "no maintained Rust decoder exists; decompress it first, e.g. `gltf-transform copy IN OUT` or `gltfpack -i IN -o OUT -noq` (which can write EXT_meshopt_compression with -cc instead)",
)];

/// One extension a file names, and what the importer does with it.
#[derive(Clone, Debug, PartialEq, Eq, serde::Serialize)]
pub struct ExtensionUse {
    /// The extension's name, as the file spells it.
    pub name: String,
    /// In `extensionsRequired`: the file cannot be drawn without it.
    pub required: bool,
    /// In [`READ`].
    pub read: bool,
}

/// Every extension in the file's `extensionsUsed` (and any required one it forgot to
/// list there), in the file's order.
pub fn uses(root: &json::Root) -> Vec<ExtensionUse> {
    let mut names: Vec<&String> = root.extensions_used.iter().collect();
    names.extend((root.extensions_required.iter()).filter(|r| !root.extensions_used.contains(r)));
    names
        .into_iter()
        .map(|name| ExtensionUse {
            name: name.clone(),
            required: root.extensions_required.contains(name),
            read: READ.contains(&name.as_str()),
        })
        .collect()
}

/// An error naming the first required extension we do not read; else clears
/// `extensionsRequired`, whose every entry we read, so that the gltf crate's validator
/// (which refuses all but its own list) passes.
pub(super) fn check_required(root: &mut json::Root) -> Step<()> {
    if let Some(name) = (root.extensions_required.iter()).find(|n| !READ.contains(&n.as_str())) {
        let remedy = REMEDIES
            .iter()
            .find(|(n, _)| n == name)
            .map_or(String::new(), |(_, r)| format!(": {r}"));
        return Err(format!(
            "the file requires the extension {name}, which stereocull does not read{remedy}"
        ));
    }
    root.extensions_required.clear();
    Ok(())
}
