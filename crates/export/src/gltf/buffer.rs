//! The single binary buffer: buffer views and accessors appended as data is written.

use gltf_json as json;
use json::accessor::{ComponentType, GenericComponentType, IndexComponentType, Type};
use json::buffer::Target;
use json::validation::{Checked, USize64};
use json::Index;

use super::meshopt::{self, Compressed, Filter};

/// Buffer views start on multiples of this (glTF 2.0 §3.6.2.4: an accessor's offset must be
/// a multiple of its component size, at most 4; vertex attributes need 4-byte alignment).
const VIEW_ALIGN: usize = 4;

/// Builds the JSON document and the one binary buffer it refers to (buffer 0).
pub(crate) struct Builder {
    /// The document; `buffers` is filled in by the caller once the data is complete.
    pub root: json::Root,
    /// The buffer's bytes, little-endian.
    pub bin: Vec<u8>,
    /// With `EXT_meshopt_compression`: the compressed views so far (animation data goes
    /// through [`Builder::animation_floats`] and [`Builder::animation_rotations`]).
    pub compressed: Option<Compressed>,
    /// Compressed three-component animation outputs go through the `EXPONENTIAL` filter
    /// (set when the key reducer measured it; else they are stored exactly).
    pub filter_vectors: bool,
    /// The `EXPONENTIAL` filter's mantissa bits.
    pub vector_bits: i32,
    /// Uncompressed animation data goes into one buffer view (accessors at offsets in it)
    /// instead of a view per accessor: less JSON (set for compact exports).
    pub group_animation: bool,
    /// That view's bytes and the accessors reading them, until [`Builder::finish_groups`].
    plain_group: meshopt::Group,
}

/// Per-component bounds of float data, for `accessor.min` / `accessor.max`.
pub(crate) enum Bounds {
    /// No `min`/`max` (not required for this accessor).
    None,
    /// Compute and write `min`/`max`.
    MinMax,
}

impl Builder {
    /// An empty document with the given `asset` header.
    pub(crate) fn new(asset: json::Asset) -> Self {
        Self {
            root: json::Root {
                asset,
                ..Default::default()
            },
            bin: Vec::new(),
            compressed: None,
            filter_vectors: false,
            vector_bits: meshopt::EXP_BITS,
            group_animation: false,
            plain_group: meshopt::Group {
                stride: 4,
                filter: Filter::None,
                raw: Vec::new(),
                accessors: Vec::new(),
            },
        }
    }

    /// Appends a buffer view holding what `write` appends to the buffer, 4-byte aligned.
    fn view(
        &mut self,
        target: Option<Target>,
        write: impl FnOnce(&mut Vec<u8>),
    ) -> Index<json::buffer::View> {
        let pad = self.bin.len().wrapping_neg() % VIEW_ALIGN;
        self.bin.resize(self.bin.len() + pad, 0);
        let offset = self.bin.len();
        write(&mut self.bin);
        let len = self.bin.len() - offset;
        self.root.push(json::buffer::View {
            buffer: Index::new(0),
            byte_length: USize64::from(len),
            byte_offset: (offset > 0).then(|| USize64::from(offset)),
            // One accessor per view, tightly packed: no byteStride needed (glTF 2.0 §3.6.2.4).
            byte_stride: None,
            name: None,
            target: target.map(Checked::Valid),
            extensions: None,
            extras: None,
        })
    }

    /// Appends a buffer view holding `bytes` as they are (an embedded image: no target).
    pub(crate) fn bytes_view(&mut self, bytes: &[u8]) -> Index<json::buffer::View> {
        self.view(None, |bin| bin.extend_from_slice(bytes))
    }

    /// Appends an accessor at offset 0 of `view`.
    fn accessor(
        &mut self,
        view: Index<json::buffer::View>,
        count: usize,
        component: ComponentType,
        type_: Type,
        bounds: Option<(json::Value, json::Value)>,
    ) -> Index<json::Accessor> {
        let (min, max) = match bounds {
            Some((lo, hi)) => (Some(lo), Some(hi)),
            None => (None, None),
        };
        self.root.push(json::Accessor {
            buffer_view: Some(view),
            byte_offset: None,
            count: USize64::from(count),
            component_type: Checked::Valid(GenericComponentType(component)),
            extensions: None,
            extras: None,
            type_: Checked::Valid(type_),
            min,
            max,
            name: None,
            normalized: false,
            sparse: None,
        })
    }

    /// A `FLOAT` accessor of `type_` elements over `data` (`data.len()` must be a multiple of
    /// the element size; the count is `data.len() / size`).
    pub(crate) fn floats(
        &mut self,
        data: &[f32],
        type_: Type,
        target: Option<Target>,
        bounds: Bounds,
    ) -> Index<json::Accessor> {
        let width = type_.multiplicity();
        let bounds = match bounds {
            Bounds::None => None,
            Bounds::MinMax => Some(min_max(data, width)),
        };
        let raw: Vec<u8> = data.iter().flat_map(|v| v.to_le_bytes()).collect();
        let view = self.vertex_view(target, &raw, 4 * width);
        self.accessor(view, data.len() / width, ComponentType::F32, type_, bounds)
    }

    /// A `FLOAT` accessor of `type_` elements over `data` (as [`Builder::floats`]) stored
    /// as a sparse accessor without a base buffer view (glTF 2.0 §3.6.2.3: the base is then
    /// all zeros): only elements with a non-zero component are written, their indices as
    /// `UNSIGNED_SHORT` (or `UNSIGNED_INT` past 65535), strictly increasing. `min`/`max`
    /// cover the full array, implicit zeros included, as the validator computes them.
    /// With no non-zero element, element 0 is stored (as zero) so that `sparse` is present.
    pub(crate) fn sparse_floats(&mut self, data: &[f32], type_: Type) -> Index<json::Accessor> {
        let width = type_.multiplicity();
        let count = data.len() / width;
        let (min, max) = min_max(data, width);
        let mut nonzero: Vec<usize> = data
            .chunks_exact(width)
            .enumerate()
            .filter(|(_, e)| e.iter().any(|&x| x != 0.0))
            .map(|(i, _)| i)
            .collect();
        // An accessor with neither bufferView nor sparse is all zeros by the spec, but
        // readers such as gltf-rs reject it: an all-zero array stores element 0 explicitly.
        if nonzero.is_empty() && count > 0 {
            nonzero.push(0);
        }
        let sparse = if nonzero.is_empty() {
            None
        } else {
            // Sparse views carry no `target`: they are not vertex attributes themselves.
            let (index_view, index_type) = if count <= usize::from(u16::MAX) + 1 {
                let view = self.view(None, |bin| {
                    for &i in &nonzero {
                        bin.extend_from_slice(&(i as u16).to_le_bytes());
                    }
                });
                (view, ComponentType::U16)
            } else {
                let view = self.view(None, |bin| {
                    for &i in &nonzero {
                        bin.extend_from_slice(&(i as u32).to_le_bytes());
                    }
                });
                (view, ComponentType::U32)
            };
            let value_view = self.view(None, |bin| {
                for &i in &nonzero {
                    for v in &data[i * width..(i + 1) * width] {
                        bin.extend_from_slice(&v.to_le_bytes());
                    }
                }
            });
            Some(json::accessor::sparse::Sparse {
                count: USize64::from(nonzero.len()),
                indices: json::accessor::sparse::Indices {
                    buffer_view: index_view,
                    byte_offset: USize64(0),
                    component_type: Checked::Valid(IndexComponentType(index_type)),
                    extensions: None,
                    extras: None,
                },
                values: json::accessor::sparse::Values {
                    buffer_view: value_view,
                    byte_offset: USize64(0),
                    extensions: None,
                    extras: None,
                },
                extensions: None,
                extras: None,
            })
        };
        self.root.push(json::Accessor {
            buffer_view: None,
            byte_offset: None,
            count: USize64::from(count),
            component_type: Checked::Valid(GenericComponentType(ComponentType::F32)),
            extensions: None,
            extras: None,
            type_: Checked::Valid(type_),
            min: Some(min),
            max: Some(max),
            name: None,
            normalized: false,
            sparse,
        })
    }

    /// Marks accessor `index` `normalized: true` (integers read as fractions, glTF 2.0
    /// §3.6.2.4), and returns it.
    fn normalized(&mut self, index: Index<json::Accessor>) -> Index<json::Accessor> {
        if let Some(accessor) = self.root.accessors.get_mut(index.value()) {
            accessor.normalized = true;
        }
        index
    }

    /// A `SHORT` accessor with `normalized: true` (`data.len() / size` elements of `type_`),
    /// read as `max(c / 32767, -1)` (glTF 2.0 §3.11): animation outputs, no bounds needed.
    pub(crate) fn normalized_i16(&mut self, data: &[i16], type_: Type) -> Index<json::Accessor> {
        let view = self.view(None, |bin| {
            for v in data {
                bin.extend_from_slice(&v.to_le_bytes());
            }
        });
        let index = self.accessor(
            view,
            data.len() / type_.multiplicity(),
            ComponentType::I16,
            type_,
            None,
        );
        self.normalized(index)
    }

    /// A compressed view of `raw` (filtered bytes, elements of `stride` bytes) in the
    /// fallback buffer (buffer 1), its encoded bytes appended to `bin`; `None` when the
    /// export is not compressed, or `raw` is unfiltered and would not get smaller.
    fn compressed_view(
        &mut self,
        raw: &[u8],
        stride: usize,
        filter: Filter,
        target: Option<Target>,
    ) -> Option<Index<json::buffer::View>> {
        let compressed = self.compressed.as_mut()?;
        let index = self.root.buffer_views.len();
        let range = compressed.push(&mut self.bin, index, raw, stride, filter)?;
        Some(self.fallback_view(range, target))
    }

    /// A view of the fallback buffer (buffer 1) over `(byte_offset, byte_length)`: its
    /// data comes from the view's `EXT_meshopt_compression` object.
    fn fallback_view(
        &mut self,
        (offset, len): (usize, usize),
        target: Option<Target>,
    ) -> Index<json::buffer::View> {
        self.root.push(json::buffer::View {
            buffer: Index::new(1),
            byte_length: USize64::from(len),
            byte_offset: (offset > 0).then(|| USize64::from(offset)),
            byte_stride: None,
            name: None,
            target: target.map(Checked::Valid),
            extensions: None,
            extras: None,
        })
    }

    /// A compressed view of triangle indices `raw` (little-endian, `stride` 2 or 4 bytes
    /// each) through the index codec; `None` when the export is not compressed or the
    /// indices are not whole triangles.
    fn compressed_indices(
        &mut self,
        raw: &[u8],
        stride: usize,
    ) -> Option<Index<json::buffer::View>> {
        let compressed = self.compressed.as_mut()?;
        let indices: Vec<u32> = match stride {
            2 => raw
                .chunks_exact(2)
                .map(|c| u32::from(u16::from_le_bytes([c[0], c[1]])))
                .collect(),
            4 => raw
                .chunks_exact(4)
                .map(|c| u32::from_le_bytes([c[0], c[1], c[2], c[3]]))
                .collect(),
            _ => return None,
        };
        let index = self.root.buffer_views.len();
        let range = compressed.push_indices(&mut self.bin, index, &indices, stride)?;
        Some(self.fallback_view(range, Some(Target::ElementArrayBuffer)))
    }

    /// A view of vertex data `raw` (elements of `stride` bytes): compressed (no filter,
    /// exact) when the export is and `target` is `ARRAY_BUFFER` with a stride the writer
    /// compresses ([`meshopt::STRIDES`]) or the data are matrices (no target, 64 bytes),
    /// triangle indices through the index codec; else as it is.
    fn vertex_view(
        &mut self,
        target: Option<Target>,
        raw: &[u8],
        stride: usize,
    ) -> Index<json::buffer::View> {
        if target == Some(Target::ElementArrayBuffer) {
            if let Some(view) = self.compressed_indices(raw, stride) {
                return view;
            }
        }
        // Attributes, and matrices (no target: inverse bind matrices).
        let attribute = target == Some(Target::ArrayBuffer) || (target.is_none() && stride == 64);
        if attribute && meshopt::STRIDES.contains(&stride) {
            if let Some(view) = self.compressed_view(raw, stride, Filter::None, target) {
                return view;
            }
        }
        self.view(target, |bin| bin.extend_from_slice(raw))
    }

    /// An animation sampler's float accessor (key times, translations, scales, weights):
    /// as [`Builder::floats`] (no target), or compressed when the export is; three-component
    /// outputs then go through the `EXPONENTIAL` filter (what
    /// [`super::meshopt::vector_as_written`] or its 16-bit form returns is what a reader gets), the rest as
    /// they are.
    pub(crate) fn animation_floats(
        &mut self,
        data: &[f32],
        type_: Type,
        bounds: Bounds,
    ) -> Index<json::Accessor> {
        let width = type_.multiplicity();
        let (raw, filter) = if width == 3 && self.filter_vectors && matches!(bounds, Bounds::None) {
            (
                meshopt::exponential(data, self.vector_bits),
                Filter::Exponential,
            )
        } else {
            (meshopt::floats(data), Filter::None)
        };
        if self.compressed.is_none() && !self.group_animation {
            return self.floats(data, type_, None, bounds);
        }
        let raw = if self.compressed.is_none() {
            meshopt::floats(data)
        } else {
            raw
        };
        let bounds = match bounds {
            Bounds::None => None,
            Bounds::MinMax => Some(min_max(data, width)),
        };
        self.grouped(&raw, 4 * width, filter, ComponentType::F32, type_, bounds)
    }

    /// An accessor over `raw` (filtered bytes, elements of `stride`) in the compressed
    /// animation group of its stride and filter: one view per group, written by
    /// [`Builder::finish_groups`] (fewer, larger views: less JSON, better compression).
    fn grouped(
        &mut self,
        raw: &[u8],
        stride: usize,
        filter: Filter,
        component: ComponentType,
        type_: Type,
        bounds: Option<(json::Value, json::Value)>,
    ) -> Index<json::Accessor> {
        // The view is set by `finish_groups`; 0 until then.
        let index = self.accessor(Index::new(0), raw.len() / stride, component, type_, bounds);
        let offset = match self.compressed.as_mut() {
            Some(compressed) => compressed.group(stride, filter, raw, index.value()),
            None => {
                // Every element size here is a multiple of 4: offsets stay aligned.
                let group = &mut self.plain_group;
                let offset = group.raw.len();
                group.raw.extend_from_slice(raw);
                group.accessors.push(index.value());
                offset
            }
        };
        if let Some(accessor) = self.root.accessors.get_mut(index.value()) {
            accessor.byte_offset = (offset > 0).then(|| USize64::from(offset));
        }
        index
    }

    /// Writes each compressed animation group, or the uncompressed one, as one view and
    /// points its accessors at it.
    pub(crate) fn finish_groups(&mut self) {
        let plain = std::mem::take(&mut self.plain_group.raw);
        if !plain.is_empty() {
            let view = self.view(None, |bin| bin.extend_from_slice(&plain));
            for accessor in std::mem::take(&mut self.plain_group.accessors) {
                if let Some(a) = self.root.accessors.get_mut(accessor) {
                    a.buffer_view = Some(view);
                }
            }
        }
        let Some(groups) = self
            .compressed
            .as_mut()
            .map(|c| std::mem::take(&mut c.groups))
        else {
            return;
        };
        for group in groups {
            let view = self
                .compressed_view(&group.raw, group.stride, group.filter, None)
                .unwrap_or_else(|| self.view(None, |bin| bin.extend_from_slice(&group.raw)));
            for accessor in group.accessors {
                if let Some(a) = self.root.accessors.get_mut(accessor) {
                    a.buffer_view = Some(view);
                }
            }
        }
    }

    /// Rotation outputs of LINEAR or STEP keys (flat xyzw, as in the track) as 16-bit
    /// normalized components: compressed through the `QUATERNION` filter (with `bits` per
    /// stored component) when the export is, else each key rounded ([`rigport_model::quantize::rotation_to_i16`]) and signs
    /// made continuous by `i16_keys`.
    pub(crate) fn animation_rotations(
        &mut self,
        values: &[f32],
        bits: u8,
        i16_keys: impl FnOnce(&[f32]) -> Vec<i16>,
    ) -> Index<json::Accessor> {
        if self.compressed.is_some() {
            let raw = meshopt::quaternions(values, bits);
            let index = self.grouped(
                &raw,
                8,
                Filter::Quaternion,
                ComponentType::I16,
                Type::Vec4,
                None,
            );
            return self.normalized(index);
        }
        let keys = i16_keys(values);
        if self.group_animation {
            return self.grouped_shorts(&keys);
        }
        self.normalized_i16(&keys, Type::Vec4)
    }

    /// `VEC4` 16-bit normalized animation outputs in the grouped animation view.
    fn grouped_shorts(&mut self, data: &[i16]) -> Index<json::Accessor> {
        let raw: Vec<u8> = data.iter().flat_map(|c| c.to_le_bytes()).collect();
        let index = self.grouped(&raw, 8, Filter::None, ComponentType::I16, Type::Vec4, None);
        self.normalized(index)
    }

    /// `VEC4` 8-bit normalized animation outputs (rotations; uncompressed exports): in the
    /// grouped animation view when there is one (4 bytes a key keeps its offsets aligned).
    pub(crate) fn animation_bytes(&mut self, data: &[i8]) -> Index<json::Accessor> {
        let raw: Vec<u8> = data.iter().flat_map(|c| c.to_le_bytes()).collect();
        let index = if self.group_animation {
            self.grouped(&raw, 4, Filter::None, ComponentType::I8, Type::Vec4, None)
        } else {
            let view = self.view(None, |bin| bin.extend_from_slice(&raw));
            self.accessor(view, data.len() / 4, ComponentType::I8, Type::Vec4, None)
        };
        self.normalized(index)
    }

    /// CUBICSPLINE rotation outputs (in-tangent, value, out-tangent per key, each xyzw) as
    /// 16-bit normalized components, rounded by the caller: compressed without a filter
    /// when the export is (the `QUATERNION` filter decodes unit quaternions, which tangents
    /// are not).
    pub(crate) fn animation_shorts(&mut self, data: &[i16]) -> Index<json::Accessor> {
        if self.compressed.is_none() && !self.group_animation {
            return self.normalized_i16(data, Type::Vec4);
        }
        self.grouped_shorts(data)
    }

    /// A vertex attribute of three `SHORT` components per element (quantized positions,
    /// `KHR_mesh_quantization`), each element padded to 8 bytes (vertex attributes align to
    /// 4 bytes: glTF 2.0 §3.6.2.4, so the view states `byteStride` 8); `min`/`max` in the
    /// stored integers with [`Bounds::MinMax`].
    pub(crate) fn padded_vec3_i16(
        &mut self,
        data: &[[i16; 3]],
        normalized: bool,
        bounds: Bounds,
    ) -> Index<json::Accessor> {
        let raw: Vec<u8> = data
            .iter()
            .flat_map(|e| [e[0], e[1], e[2], 0])
            .flat_map(i16::to_le_bytes)
            .collect();
        let bounds = match bounds {
            Bounds::None => None,
            Bounds::MinMax => {
                // Integers, as the components are (`-32767`, not `-32767.0`).
                let fold = |pick: fn(i16, i16) -> i16, start: i16| {
                    let bound = data.iter().fold([start; 3], |acc, e| {
                        [pick(acc[0], e[0]), pick(acc[1], e[1]), pick(acc[2], e[2])]
                    });
                    json::Value::Array(bound.iter().map(|&c| json::Value::from(c)).collect())
                };
                Some((fold(i16::min, i16::MAX), fold(i16::max, i16::MIN)))
            }
        };
        self.padded_vertex(&raw, 8, data.len(), ComponentType::I16, normalized, bounds)
    }

    /// Unit `normals` as a vertex attribute of three `BYTE` normalized components per
    /// element (`KHR_mesh_quantization`), each element padded to 4 bytes: each component
    /// rounded to the nearest `k / 127`, or through meshopt's `OCTAHEDRAL` filter when the
    /// export is compressed.
    pub(crate) fn normals_i8(&mut self, normals: &[[f32; 3]]) -> Index<json::Accessor> {
        let view = match self.compressed.is_some() {
            true => {
                let raw = meshopt::octahedral(normals);
                self.compressed_view(&raw, 4, Filter::Octahedral, Some(Target::ArrayBuffer))
            }
            false => None,
        };
        let view = view.unwrap_or_else(|| {
            let raw: Vec<u8> = normals
                .iter()
                .flat_map(|n| [n[0], n[1], n[2], 0.0])
                .map(|c| ((c * 127.0).round().clamp(-127.0, 127.0) as i8).to_le_bytes()[0])
                .collect();
            self.vertex_view(Some(Target::ArrayBuffer), &raw, 4)
        });
        self.vec3_at_stride(view, 4, normals.len(), ComponentType::I8, true, None)
    }

    /// A `VEC3` vertex attribute over `raw` (`count` elements of `stride` bytes, padded),
    /// in a view of its own that states the stride.
    fn padded_vertex(
        &mut self,
        raw: &[u8],
        stride: usize,
        count: usize,
        component: ComponentType,
        normalized: bool,
        bounds: Option<(json::Value, json::Value)>,
    ) -> Index<json::Accessor> {
        let view = self.vertex_view(Some(Target::ArrayBuffer), raw, stride);
        self.vec3_at_stride(view, stride, count, component, normalized, bounds)
    }

    /// A `VEC3` vertex attribute in `view`, whose `byteStride` it states.
    fn vec3_at_stride(
        &mut self,
        view: Index<json::buffer::View>,
        stride: usize,
        count: usize,
        component: ComponentType,
        normalized: bool,
        bounds: Option<(json::Value, json::Value)>,
    ) -> Index<json::Accessor> {
        if let Some(v) = self.root.buffer_views.get_mut(view.value()) {
            v.byte_stride = Some(json::buffer::Stride(stride));
        }
        let index = self.accessor(view, count, component, Type::Vec3, bounds);
        if let Some(accessor) = self.root.accessors.get_mut(index.value()) {
            accessor.normalized = normalized;
        }
        index
    }

    /// An `UNSIGNED_BYTE` accessor with `normalized: true` (read as `c / 255`), for vertex
    /// weights.
    pub(crate) fn normalized_u8(
        &mut self,
        data: &[u8],
        type_: Type,
        target: Option<Target>,
    ) -> Index<json::Accessor> {
        let index = self.ints(data, type_, target);
        self.normalized(index)
    }

    /// An unsigned-integer accessor (`data.len() / size` elements of `type_`), of `T`'s
    /// component type (`u8`, `u16` or `u32`).
    pub(crate) fn ints<T: IntComponent>(
        &mut self,
        data: &[T],
        type_: Type,
        target: Option<Target>,
    ) -> Index<json::Accessor> {
        let mut raw = Vec::with_capacity(data.len() * 4);
        for v in data {
            v.put_le(&mut raw);
        }
        let stride = raw.len() / (data.len() / type_.multiplicity()).max(1);
        let view = self.vertex_view(target, &raw, stride);
        self.accessor(
            view,
            data.len() / type_.multiplicity(),
            T::COMPONENT,
            type_,
            None,
        )
    }
}

/// Per-component min and max of `data` viewed as elements of `width` floats.
///
/// Each bound is written as the exact `f64` value of the `f32` (e.g. `0.10000000149011612`,
/// not `0.1`): the validator compares the declared bound with the data read as `f32`, so the
/// JSON number must parse back to the very same value whatever the reader's precision.
fn min_max(data: &[f32], width: usize) -> (json::Value, json::Value) {
    let mut lo = vec![f32::INFINITY; width];
    let mut hi = vec![f32::NEG_INFINITY; width];
    for element in data.chunks_exact(width) {
        for (c, &v) in element.iter().enumerate() {
            lo[c] = lo[c].min(v);
            hi[c] = hi[c].max(v);
        }
    }
    // Each bound as the shortest decimal that reads back as the same f32 (`-98.97249`, not
    // the f64 expansion `-98.97248840332031`; whole numbers without `.0`): glTF 2.0
    // (3.6.2.5) has readers round a float accessor's bounds to single precision, and the
    // JSON is shorter.
    let to_json = |v: Vec<f32>| {
        json::Value::Array(
            v.into_iter()
                .map(|x| match x.fract() == 0.0 && x.abs() < 16_777_216.0 {
                    // `0`, not `0.0`.
                    true => json::Value::from(x as i64),
                    false => {
                        json::Value::from(format!("{x}").parse::<f64>().unwrap_or(f64::from(x)))
                    }
                })
                .collect(),
        )
    };
    (to_json(lo), to_json(hi))
}

/// An unsigned integer glTF stores little-endian as an accessor component.
pub(crate) trait IntComponent: Copy {
    /// The accessor's component type.
    const COMPONENT: ComponentType;
    /// Appends the little-endian bytes.
    fn put_le(self, out: &mut Vec<u8>);
}

macro_rules! int_component {
    ($t:ty, $c:expr) => {
        impl IntComponent for $t {
            const COMPONENT: ComponentType = $c;
            fn put_le(self, out: &mut Vec<u8>) {
                out.extend_from_slice(&self.to_le_bytes());
            }
        }
    };
}
int_component!(u8, ComponentType::U8);
int_component!(u16, ComponentType::U16);
int_component!(u32, ComponentType::U32);

#[cfg(test)]
mod tests {
    use super::*;

    fn builder() -> Builder {
        Builder::new(json::Asset {
            version: "2.0".into(),
            ..Default::default()
        })
    }

    fn u16_at(bin: &[u8], view: &json::buffer::View, k: usize) -> u16 {
        let at = view.byte_offset.map_or(0, |o| o.0 as usize) + 2 * k;
        u16::from_le_bytes([bin[at], bin[at + 1]])
    }

    #[test]
    fn sparse_floats_store_only_non_zero_elements_with_full_bounds() {
        let mut b = builder();
        // Elements 1 and 3 move; min/max must include the implicit zeros.
        let data = [
            0.0, 0.0, 0.0, 1.0, 2.0, 3.0, 0.0, 0.0, 0.0, 0.5, -4.0, 0.0, 0.0, 0.0, 0.0,
        ];
        let acc = b.sparse_floats(&data, Type::Vec3);
        let a = &b.root.accessors[acc.value()];
        assert!(a.buffer_view.is_none());
        assert_eq!(a.count.0, 5);
        // Whole numbers without `.0`.
        assert_eq!(a.min, Some(serde_json::json!([0, -4, 0])));
        assert_eq!(a.max, Some(serde_json::json!([1, 2, 3])));
        let sparse = a.sparse.as_ref().unwrap();
        assert_eq!(sparse.count.0, 2);
        let iv = &b.root.buffer_views[sparse.indices.buffer_view.value()];
        assert!(iv.target.is_none());
        assert_eq!((u16_at(&b.bin, iv, 0), u16_at(&b.bin, iv, 1)), (1, 3));
        let vv = &b.root.buffer_views[sparse.values.buffer_view.value()];
        assert_eq!(vv.byte_length.0, 24);
        let at = vv.byte_offset.map_or(0, |o| o.0 as usize);
        let values: Vec<f32> = b.bin[at..at + 24]
            .chunks_exact(4)
            .map(|c| f32::from_le_bytes([c[0], c[1], c[2], c[3]]))
            .collect();
        assert_eq!(values, [1.0, 2.0, 3.0, 0.5, -4.0, 0.0]);
        assert_eq!(at % 4, 0, "value view is 4-byte aligned");
    }

    #[test]
    fn all_zero_sparse_floats_keep_one_explicit_element() {
        let mut b = builder();
        let acc = b.sparse_floats(&[0.0; 9], Type::Vec3);
        let a = &b.root.accessors[acc.value()];
        assert_eq!(a.sparse.as_ref().unwrap().count.0, 1);
        assert_eq!(a.min, Some(serde_json::json!([0, 0, 0])));
    }

    #[test]
    fn float_bounds_are_the_shortest_text_of_their_f32() {
        let (lo, hi) = min_max(&[-98.972_49, 0.1, 3.0, 1e-7], 2);
        assert_eq!(lo.to_string(), "[-98.97249,1e-7]");
        assert_eq!(hi.to_string(), "[3,0.1]");
        // Each reads back as the same f32.
        for (text, x) in [("-98.97249", -98.972_49_f32), ("0.1", 0.1), ("1e-7", 1e-7)] {
            assert_eq!(text.parse::<f64>().unwrap() as f32, x);
        }
    }
}
