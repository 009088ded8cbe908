//! Reading accessors: any element type through gltf's reader (with what the reader
//! assumes checked first), and vertex attributes of any component type as floats
//! (`KHR_mesh_quantization`'s bytes and shorts, normalized or not, by glTF's equations).

use gltf::accessor::{DataType, Dimensions, Item};

use super::{Importer, Step};

impl Importer<'_> {
    pub(super) fn read<T: Item>(&self, index: u64, where_: &dyn Fn() -> String) -> Step<Vec<T>> {
        self.items(&self.accessor(index, where_)?, &where_())
    }

    /// [`Importer::floats`] of accessor `index`.
    pub(super) fn read_floats<const N: usize>(
        &self,
        index: u64,
        where_: &dyn Fn() -> String,
    ) -> Step<Vec<[f32; N]>>
    where
        [f32; N]: Item,
        [i8; N]: Item,
        [u8; N]: Item,
        [i16; N]: Item,
        [u16; N]: Item,
    {
        self.floats(&self.accessor(index, where_)?, &where_())
    }

    fn accessor(&self, index: u64, where_: &dyn Fn() -> String) -> Step<gltf::Accessor<'_>> {
        (self.document.accessors().nth(index as usize))
            .ok_or_else(|| format!("{}: accessor {index} does not exist", where_()))
    }

    /// The accessor's elements of N components as floats: floats as they are, and
    /// (core glTF for some attributes, `KHR_mesh_quantization` for all) bytes and
    /// shorts, signed or not, as integers or, where normalized, mapped onto [-1, 1] or
    /// [0, 1] as the specification's equations say.
    pub(super) fn floats<const N: usize>(
        &self,
        accessor: &gltf::Accessor,
        what: &str,
    ) -> Step<Vec<[f32; N]>>
    where
        [f32; N]: Item,
        [i8; N]: Item,
        [u8; N]: Item,
        [i16; N]: Item,
        [u16; N]: Item,
    {
        let dimensions = [Dimensions::Vec2, Dimensions::Vec3, Dimensions::Vec4];
        if accessor.dimensions() != dimensions[N.clamp(2, 4) - 2] {
            return Err(format!(
                "{what}: accessors[{}] holds {:?} {:?}; {N} components are expected here",
                accessor.index(),
                accessor.dimensions(),
                accessor.data_type()
            ));
        }
        let normalized = accessor.normalized();
        let signed = |max: f32| move |c: f32| if normalized { (c / max).max(-1.0) } else { c };
        let unsigned = |max: f32| move |c: f32| if normalized { c / max } else { c };
        match accessor.data_type() {
            DataType::F32 => self.items(accessor, what),
            DataType::I8 => Ok(scaled(
                self.items::<[i8; N]>(accessor, what)?,
                signed(127.0),
            )),
            DataType::U8 => Ok(scaled(
                self.items::<[u8; N]>(accessor, what)?,
                unsigned(255.0),
            )),
            DataType::I16 => Ok(scaled(
                self.items::<[i16; N]>(accessor, what)?,
                signed(32767.0),
            )),
            DataType::U16 => Ok(scaled(
                self.items::<[u16; N]>(accessor, what)?,
                unsigned(65535.0),
            )),
            other => Err(format!(
                "{what}: accessors[{}] holds {:?} {other:?}; attributes are floats, bytes or shorts",
                accessor.index(),
                accessor.dimensions(),
            )),
        }
    }

    /// The accessor's elements as `T`, once [`check_accessor`] holds for `T`.
    pub(super) fn items<T: Item>(&self, accessor: &gltf::Accessor, what: &str) -> Step<Vec<T>> {
        check_accessor(accessor, std::mem::size_of::<T>(), what)?;
        let iter = gltf::accessor::Iter::<T>::new(accessor.clone(), |b| {
            self.buffers.get(b.index()).map(|d| &d.0[..])
        })
        .ok_or_else(|| {
            format!(
                "{what}: accessors[{}] has no readable data",
                accessor.index()
            )
        })?;
        Ok(iter.collect())
    }
}

/// What gltf 1.4's accessor reader assumes without checking (debug assertions in debug
/// builds, an unchecked `count - 1`): an element of the size read, a stride no smaller,
/// and at least one element. Found by the fuzz targets; see `fuzz/regressions/`.
pub(super) fn check_accessor(accessor: &gltf::Accessor, element: usize, what: &str) -> Step<()> {
    let fail = |m: String| Err(format!("{what}: accessors[{}] {m}", accessor.index()));
    if accessor.count() == 0 || accessor.sparse().is_some_and(|s| s.count() == 0) {
        return fail("has count 0 (at least 1 is required)".into());
    }
    if accessor.size() != element {
        return fail(format!(
            "holds {:?} {:?} ({} bytes); {element}-byte elements are expected here",
            accessor.dimensions(),
            accessor.data_type(),
            accessor.size()
        ));
    }
    match accessor.view().and_then(|v| v.stride()) {
        Some(stride) if stride < element => fail(format!(
            "has byteStride {stride}, below its {element}-byte element"
        )),
        _ => Ok(()),
    }
}

/// Each component of `elements` through `scale`.
fn scaled<T: Copy + Into<f32>, const N: usize>(
    elements: Vec<[T; N]>,
    scale: impl Fn(f32) -> f32,
) -> Vec<[f32; N]> {
    (elements.into_iter())
        .map(|e| e.map(|c| scale(c.into())))
        .collect()
}
