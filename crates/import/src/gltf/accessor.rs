//! Accessors: range checks before every read (glTF 2.0 §3.6), and typed readers.

use ::gltf::accessor::{DataType, Dimensions};
use ::gltf::mesh::util::{ReadIndices, ReadJoints, ReadWeights};
use rigport_model::glam::{Vec2, Vec3};

use crate::ImportError;

use super::importer::Importer;

/// Largest size in bytes of an accessor without a `bufferView` (zeros, optionally with
/// sparse values): its size is not bounded by the file's bytes, so it is capped to keep
/// hostile files from exhausting memory. 256 MiB is 22 million `VEC3` floats.
const MAX_ZERO_FILLED_BYTES: usize = 1 << 28;

fn type_name(d: Dimensions) -> &'static str {
    match d {
        Dimensions::Scalar => "SCALAR",
        Dimensions::Vec2 => "VEC2",
        Dimensions::Vec3 => "VEC3",
        Dimensions::Vec4 => "VEC4",
        Dimensions::Mat2 => "MAT2",
        Dimensions::Mat3 => "MAT3",
        Dimensions::Mat4 => "MAT4",
    }
}

fn component_name(t: DataType) -> &'static str {
    match t {
        DataType::I8 => "BYTE",
        DataType::U8 => "UNSIGNED_BYTE",
        DataType::I16 => "SHORT",
        DataType::U16 => "UNSIGNED_SHORT",
        DataType::U32 => "UNSIGNED_INT",
        DataType::F32 => "FLOAT",
    }
}

pub(super) const FLOAT: &[DataType] = &[DataType::F32];
/// Float or normalized integers, as glTF allows for texture coordinates and weights.
pub(super) const FLOAT_OR_UNORM: &[DataType] = &[DataType::F32, DataType::U8, DataType::U16];
/// Float or integers of either sign: normalized for rotation and morph-weight outputs; for
/// mesh attributes (positions, normals, texture coordinates, morph target deltas) under
/// `KHR_mesh_quantization`, normalized or not.
pub(super) const FLOAT_OR_NORM: &[DataType] = &[
    DataType::F32,
    DataType::I8,
    DataType::U8,
    DataType::I16,
    DataType::U16,
];

impl<'a> Importer<'a> {
    /// Whether the file uses `KHR_mesh_quantization` (integer mesh attributes).
    fn quantized(&self) -> bool {
        self.doc
            .extensions_used()
            .any(|e| e == "KHR_mesh_quantization")
    }

    /// The elements of a `N`-component accessor of any component type, as floats: a
    /// normalized integer as glTF 2.0 (3.11, "Animations" and 3.6.2.2) maps it (`c / 127`
    /// at least -1, `c / 255`, `c / 32767` at least -1, `c / 65535`), any other integer as
    /// its value.
    fn floats<const N: usize>(
        &self,
        acc: &::gltf::Accessor<'a>,
        at: &str,
    ) -> Result<Vec<[f32; N]>, ImportError>
    where
        [i8; N]: ::gltf::accessor::Item,
        [u8; N]: ::gltf::accessor::Item,
        [i16; N]: ::gltf::accessor::Item,
        [u16; N]: ::gltf::accessor::Item,
        [f32; N]: ::gltf::accessor::Item,
    {
        let norm = acc.normalized();
        let scale = |max: f32, c: f32| if norm { (c / max).max(-1.0) } else { c };
        Ok(match acc.data_type() {
            DataType::I8 => self
                .iter::<[i8; N]>(acc, at)?
                .map(|v| v.map(|c| scale(127.0, f32::from(c))))
                .collect(),
            DataType::U8 => self
                .iter::<[u8; N]>(acc, at)?
                .map(|v| v.map(|c| scale(255.0, f32::from(c))))
                .collect(),
            DataType::I16 => self
                .iter::<[i16; N]>(acc, at)?
                .map(|v| v.map(|c| scale(32767.0, f32::from(c))))
                .collect(),
            DataType::U16 => self
                .iter::<[u16; N]>(acc, at)?
                .map(|v| v.map(|c| scale(65535.0, f32::from(c))))
                .collect(),
            _ => self.iter::<[f32; N]>(acc, at)?.collect(),
        })
    }

    /// Checks everything the `gltf` readers assume: element type, count, and that every
    /// byte read lies inside its buffer view and buffer. Returns the element count.
    pub(super) fn check(
        &self,
        acc: &::gltf::Accessor<'_>,
        dims: Dimensions,
        types: &[DataType],
        at: &str,
    ) -> Result<usize, ImportError> {
        let what = format!("accessor {}", acc.index());
        if acc.dimensions() != dims || !types.contains(&acc.data_type()) {
            let allowed: Vec<&str> = types.iter().map(|t| component_name(*t)).collect();
            return Err(self.err(
                at,
                format!(
                    "{what} is {} of {}; expected {} of {}",
                    type_name(acc.dimensions()),
                    component_name(acc.data_type()),
                    type_name(dims),
                    allowed.join(" or ")
                ),
            ));
        }
        let count = acc.count();
        if count == 0 {
            return Err(self.err(at, format!("{what} has count 0")));
        }
        let elem = acc.size();
        match acc.view() {
            Some(view) => self.check_view_range(&view, acc.offset(), count, elem, at, &what)?,
            None if count.saturating_mul(elem) > MAX_ZERO_FILLED_BYTES => {
                return Err(self.err(
                    at,
                    format!(
                        "{what} has no bufferView and {count} elements of {elem} bytes; \
                         rigport accepts at most {MAX_ZERO_FILLED_BYTES} bytes"
                    ),
                ))
            }
            None => {}
        }
        if let Some(sparse) = acc.sparse() {
            let sparse_count = sparse.count();
            if sparse_count == 0 || sparse_count > count {
                return Err(self.err(
                    at,
                    format!("{what} has sparse.count {sparse_count} for {count} elements"),
                ));
            }
            let indices = sparse.indices();
            let index_size = match indices.index_type() {
                ::gltf::accessor::sparse::IndexType::U8 => 1,
                ::gltf::accessor::sparse::IndexType::U16 => 2,
                ::gltf::accessor::sparse::IndexType::U32 => 4,
            };
            self.check_view_range(
                &indices.view(),
                indices.offset(),
                sparse_count,
                index_size,
                at,
                &format!("{what} sparse indices"),
            )?;
            let values = sparse.values();
            self.check_view_range(
                &values.view(),
                values.offset(),
                sparse_count,
                elem,
                at,
                &format!("{what} sparse values"),
            )?;
        }
        Ok(count)
    }

    /// `count >= 1` elements of `elem` bytes from `offset` in `view`, strided as the view says.
    fn check_view_range(
        &self,
        view: &::gltf::buffer::View<'_>,
        offset: usize,
        count: usize,
        elem: usize,
        at: &str,
        what: &str,
    ) -> Result<(), ImportError> {
        let stride = view.stride().unwrap_or(elem);
        if stride < elem {
            return Err(self.err(
                at,
                format!(
                    "{what}: buffer view {} has byteStride {stride}, less than the element \
                     size {elem}",
                    view.index()
                ),
            ));
        }
        let end = stride
            .checked_mul(count.saturating_sub(1))
            .and_then(|x| x.checked_add(elem))
            .and_then(|x| x.checked_add(offset));
        if end.is_none_or(|end| end > view.length()) {
            return Err(self.err(
                at,
                format!(
                    "{what} reads {count} elements of {elem} bytes (stride {stride}) from byte \
                     {offset} of buffer view {}, which holds {} bytes",
                    view.index(),
                    view.length()
                ),
            ));
        }
        let buffer = view.buffer().index();
        let buffer_len = self.buffers.get(buffer).map_or(0, |b| b.len());
        if view
            .offset()
            .checked_add(view.length())
            .is_none_or(|end| end > buffer_len)
        {
            return Err(self.err(
                at,
                format!(
                    "{what}: buffer view {} spans bytes {}..{} of buffer {buffer}, which holds \
                     {buffer_len} bytes",
                    view.index(),
                    view.offset(),
                    view.offset().saturating_add(view.length())
                ),
            ));
        }
        Ok(())
    }

    /// Whether the accessor has neither `bufferView` nor `sparse`: all zeros (glTF 2.0
    /// §3.6.2.1), which the `gltf` readers do not produce.
    pub(super) fn zero_filled(acc: &::gltf::Accessor<'_>) -> bool {
        acc.view().is_none() && acc.sparse().is_none()
    }

    fn iter<T: ::gltf::accessor::Item>(
        &self,
        acc: &::gltf::Accessor<'a>,
        at: &str,
    ) -> Result<::gltf::accessor::Iter<'a, T>, ImportError> {
        ::gltf::accessor::Iter::new(acc.clone(), self.data())
            .ok_or_else(|| self.err(at, format!("accessor {} data unavailable", acc.index())))
    }

    pub(super) fn read_vec3(
        &self,
        acc: &::gltf::Accessor<'a>,
        at: &str,
    ) -> Result<Vec<Vec3>, ImportError> {
        let types = if self.quantized() {
            FLOAT_OR_NORM
        } else {
            FLOAT
        };
        let count = self.check(acc, Dimensions::Vec3, types, at)?;
        if Self::zero_filled(acc) {
            return Ok(vec![Vec3::ZERO; count]);
        }
        let values: Vec<Vec3> = self
            .floats::<3>(acc, at)?
            .into_iter()
            .map(Vec3::from)
            .collect();
        if let Some(k) = values.iter().position(|v| !v.is_finite()) {
            return Err(self.err(at, format!("element {k} is not finite: {}", values[k])));
        }
        Ok(values)
    }

    pub(super) fn read_scalars(
        &self,
        acc: &::gltf::Accessor<'a>,
        at: &str,
    ) -> Result<Vec<f32>, ImportError> {
        let count = self.check(acc, Dimensions::Scalar, FLOAT, at)?;
        if Self::zero_filled(acc) {
            return Ok(vec![0.0; count]);
        }
        Ok(self.iter::<f32>(acc, at)?.collect())
    }

    pub(super) fn read_tex_coords(
        &self,
        acc: &::gltf::Accessor<'a>,
        at: &str,
    ) -> Result<Vec<Vec2>, ImportError> {
        let types = if self.quantized() {
            FLOAT_OR_NORM
        } else {
            FLOAT_OR_UNORM
        };
        let count = self.check(acc, Dimensions::Vec2, types, at)?;
        if Self::zero_filled(acc) {
            return Ok(vec![Vec2::ZERO; count]);
        }
        let values: Vec<Vec2> = self
            .floats::<2>(acc, at)?
            .into_iter()
            .map(Vec2::from)
            .collect();
        if let Some(k) = values.iter().position(|v| !v.is_finite()) {
            return Err(self.err(at, format!("element {k} is not finite: {}", values[k])));
        }
        Ok(values)
    }

    pub(super) fn read_indices(
        &self,
        acc: &::gltf::Accessor<'a>,
        at: &str,
    ) -> Result<Vec<u32>, ImportError> {
        let count = self.check(
            acc,
            Dimensions::Scalar,
            &[DataType::U8, DataType::U16, DataType::U32],
            at,
        )?;
        if Self::zero_filled(acc) {
            return Ok(vec![0; count]);
        }
        let read = match acc.data_type() {
            DataType::U8 => ReadIndices::U8(self.iter(acc, at)?),
            DataType::U16 => ReadIndices::U16(self.iter(acc, at)?),
            _ => ReadIndices::U32(self.iter(acc, at)?),
        };
        Ok(read.into_u32().collect())
    }

    pub(super) fn read_joints(
        &self,
        acc: &::gltf::Accessor<'a>,
        at: &str,
    ) -> Result<Vec<[u16; 4]>, ImportError> {
        let count = self.check(acc, Dimensions::Vec4, &[DataType::U8, DataType::U16], at)?;
        if Self::zero_filled(acc) {
            return Ok(vec![[0; 4]; count]);
        }
        let read = match acc.data_type() {
            DataType::U8 => ReadJoints::U8(self.iter(acc, at)?),
            _ => ReadJoints::U16(self.iter(acc, at)?),
        };
        Ok(read.into_u16().collect())
    }

    pub(super) fn read_weights(
        &self,
        acc: &::gltf::Accessor<'a>,
        at: &str,
    ) -> Result<Vec<[f32; 4]>, ImportError> {
        let count = self.check(acc, Dimensions::Vec4, FLOAT_OR_UNORM, at)?;
        if Self::zero_filled(acc) {
            return Ok(vec![[0.0; 4]; count]);
        }
        let read = match acc.data_type() {
            DataType::U8 => ReadWeights::U8(self.iter(acc, at)?),
            DataType::U16 => ReadWeights::U16(self.iter(acc, at)?),
            _ => ReadWeights::F32(self.iter(acc, at)?),
        };
        Ok(read.into_f32().collect())
    }
}
