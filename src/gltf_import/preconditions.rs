//! What the gltf crate (1.4.1) assumes of a document and does not check: its accessors
//! `unwrap` these, so a malformed file would panic inside them. [`check`] runs on the
//! JSON before any of them is called and turns each into an error naming the part.
//!
//! The gltf accessors the importer calls (and those skins, animations and materials will
//! call), and why each cannot panic once [`check`] and `Document::from_json` have passed:
//!
//! - Every `Index<T>` the crate resolves with `.nth(i).unwrap()` (a node's mesh and
//!   children, a primitive's attributes, indices and material, an accessor's or an
//!   image's buffer view, a view's buffer, a texture's source and sampler, a texture
//!   info's texture, a skin's joints, skeleton and inverse bind matrices, an animation
//!   sampler's input and output, the default scene): `Document::from_json` validates each
//!   against its array (`IndexOutOfBounds`), except POSITION, whose validator itself
//!   indexes unchecked: `parse` checks it first (`super::parse`).
//! - Every `Checked<T>` the crate unwraps (an accessor's component type and type, a
//!   primitive's mode, a material's alpha mode, a sampler's filters and wrap modes, a
//!   view's target, an animation sampler's interpolation): `from_json` reports
//!   `Invalid` values.
//! - `Image::source` unwraps the `mimeType` of an image in a buffer view and the `uri`
//!   of one without: not validated. [`check`]: every image has exactly one of `uri` and
//!   `bufferView`, and a `bufferView` image has a `mimeType` (the spec requires both).
//! - `gltf::import_buffers` percent-decodes a relative buffer `uri` and unwraps the
//!   result: not validated. [`check`]: every relative buffer `uri` decodes (with the same
//!   `urlencoding` crate) to UTF-8. Images are read by the importer itself
//!   (`materials.rs`), which does not decode.
//! - `animation::Channel::target().node()` and `property()`: an animation's validator
//!   checks its samplers and each channel's sampler index, but not the channels'
//!   targets. [`check`]: every channel's target node exists and its path is valid.
//! - Sparse accessors: the sparse iterator unwraps a value per sparse index, and both
//!   iterators have the sparse `count` elements (the reader returns `None` when a view
//!   is too short for it), so it never runs out.
//! - `Primitive::bounding_box` unwraps POSITION's `min` and `max`, which `from_json`
//!   requires; the importer computes its own bounds anyway.
//! - Texture transforms (`KHR_texture_transform`) are plain optional fields: nothing to
//!   unwrap.
//! - `Reader::read_tex_coords` is `unreachable!` on a component type other than float,
//!   unsigned byte and unsigned short, and asserts two components (found by fuzzing).
//!   The importer no longer calls it: it reads every vertex attribute through
//!   `Importer::floats`, which checks the components and the component type first.

use gltf::json;

use super::Step;

/// Every precondition of the list above that `Document::from_json` does not check.
pub(super) fn check(root: &json::Root) -> Step<()> {
    for (i, image) in root.images.iter().enumerate() {
        image_source(i, image)?;
    }
    for (i, buffer) in root.buffers.iter().enumerate() {
        buffer_uri(i, buffer)?;
    }
    for (a, animation) in root.animations.iter().enumerate() {
        channel_targets(a, animation, root.nodes.len())?;
    }
    Ok(())
}

fn image_source(i: usize, image: &json::Image) -> Step<()> {
    let name = image
        .name
        .as_deref()
        .map_or(String::new(), |n| format!(" ({n:?})"));
    match (&image.uri, &image.buffer_view, &image.mime_type) {
        (None, None, _) => Err(format!(
            "images[{i}]{name} has neither a uri nor a bufferView: its pixels are nowhere"
        )),
        (Some(_), Some(_), _) => Err(format!(
            "images[{i}]{name} has both a uri and a bufferView (exactly one is allowed)"
        )),
        (None, Some(_), None) => Err(format!(
            "images[{i}]{name} lies in a bufferView but has no mimeType (required there)"
        )),
        _ => Ok(()),
    }
}

fn buffer_uri(i: usize, buffer: &json::Buffer) -> Step<()> {
    match &buffer.uri {
        Some(uri) if !uri.contains(':') && urlencoding::decode(uri).is_err() => Err(format!(
            "buffers[{i}].uri {uri:?} percent-decodes to bytes that are not UTF-8"
        )),
        _ => Ok(()),
    }
}

fn channel_targets(a: usize, animation: &json::Animation, nodes: usize) -> Step<()> {
    for (c, channel) in animation.channels.iter().enumerate() {
        let at = format!("animations[{a}].channels[{c}].target");
        let node = channel.target.node.value();
        if node >= nodes {
            return Err(format!(
                "{at}.node: node {node} does not exist (the file has {nodes})"
            ));
        }
        if !matches!(channel.target.path, json::validation::Checked::Valid(_)) {
            return Err(format!("{at}.path is not a property glTF defines"));
        }
    }
    Ok(())
}
