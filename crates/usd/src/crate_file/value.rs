//! Value representations (`ValueRep`) decoded into the text parser's [`Value`]s.
//!
//! Type numbers are `pxr/usd/usd/crateDataTypes.h`; reading follows `crateFile.cpp`'s
//! `_Reader` (heap values), `crateValueInliners.h` (inlined values) and
//! `_ReadPossiblyCompressedArray` (arrays).

use super::coding::{self, Width};
use super::layout::{CrateFile, Cursor, MAX_VALUE_DEPTH};
use crate::error::{CrateProblem, Nesting, Problem, UsdError};
use crate::layer::{ListOp, Value};

/// A crate type number (`Usd_CrateFile::TypeEnum`).
pub(crate) type TypeId = u8;

mod ty {
    // Named from the crate root: tools/module_cycles.py reads a `super::` in an inline
    // module as the file's parent (mod.rs), which would count as a dependency on it.
    use crate::crate_file::value::TypeId;
    pub const BOOL: TypeId = 1;
    pub const UCHAR: TypeId = 2;
    pub const INT: TypeId = 3;
    pub const UINT: TypeId = 4;
    pub const INT64: TypeId = 5;
    pub const UINT64: TypeId = 6;
    pub const HALF: TypeId = 7;
    pub const FLOAT: TypeId = 8;
    pub const DOUBLE: TypeId = 9;
    pub const STRING: TypeId = 10;
    pub const TOKEN: TypeId = 11;
    pub const ASSET_PATH: TypeId = 12;
    pub const MATRIX2D: TypeId = 13;
    pub const MATRIX3D: TypeId = 14;
    pub const MATRIX4D: TypeId = 15;
    pub const QUATD: TypeId = 16;
    pub const QUATF: TypeId = 17;
    pub const QUATH: TypeId = 18;
    pub const VEC2D: TypeId = 19;
    pub const VEC4I: TypeId = 30;
    pub const DICTIONARY: TypeId = 31;
    pub const TOKEN_LIST_OP: TypeId = 32;
    pub const STRING_LIST_OP: TypeId = 33;
    pub const PATH_LIST_OP: TypeId = 34;
    pub const REFERENCE_LIST_OP: TypeId = 35;
    pub const INT_LIST_OP: TypeId = 36;
    pub const INT64_LIST_OP: TypeId = 37;
    pub const UINT_LIST_OP: TypeId = 38;
    pub const UINT64_LIST_OP: TypeId = 39;
    pub const PATH_VECTOR: TypeId = 40;
    pub const TOKEN_VECTOR: TypeId = 41;
    pub const SPECIFIER: TypeId = 42;
    pub const PERMISSION: TypeId = 43;
    pub const VARIABILITY: TypeId = 44;
    pub const VARIANT_SELECTION_MAP: TypeId = 45;
    pub const TIME_SAMPLES: TypeId = 46;
    pub const PAYLOAD: TypeId = 47;
    pub const DOUBLE_VECTOR: TypeId = 48;
    pub const LAYER_OFFSET_VECTOR: TypeId = 49;
    pub const STRING_VECTOR: TypeId = 50;
    pub const VALUE_BLOCK: TypeId = 51;
    pub const VALUE: TypeId = 52;
    pub const UNREGISTERED_VALUE: TypeId = 53;
    pub const UNREGISTERED_VALUE_LIST_OP: TypeId = 54;
    pub const PAYLOAD_LIST_OP: TypeId = 55;
    pub const TIME_CODE: TypeId = 56;
    pub const PATH_EXPRESSION: TypeId = 57;
    pub const RELOCATES: TypeId = 58;
}

/// Arrays shorter than this are never stored compressed (`MinCompressedArraySize`).
const MIN_COMPRESSED_ARRAY: usize = 16;

/// A decoded field value.
#[derive(Clone, Debug, PartialEq)]
pub(crate) enum Decoded {
    /// A value as the text format would write it.
    Value(Value),
    /// A list op: its non-empty operations, in the order the text writes them.
    ListOp(Vec<(ListOp, Vec<Value>)>),
    /// Time samples: (time code, value); a blocked sample is `Value::None`.
    Samples(Vec<(f64, Value)>),
    /// A type this reader does not know (newer crate versions): left out.
    Unsupported(TypeId),
}

/// The parts of a value representation.
#[derive(Clone, Copy, Debug)]
struct Rep {
    ty: TypeId,
    array: bool,
    inlined: bool,
    compressed: bool,
    payload: u64,
}

impl Rep {
    fn new(bits: u64) -> Self {
        Self {
            ty: ((bits >> 48) & 0xff) as TypeId,
            array: bits & (1 << 63) != 0,
            inlined: bits & (1 << 62) != 0,
            compressed: bits & (1 << 61) != 0,
            payload: bits & ((1 << 48) - 1),
        }
    }
}

/// The shape of a fixed-size element type: component kind and count.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Scalar {
    Half,
    Float,
    Double,
    Int,
}

/// Vector, matrix and quaternion types: (scalar, components, rows for matrices,
/// quaternion).
fn shape(t: TypeId) -> Option<(Scalar, usize, usize, bool)> {
    use Scalar::*;
    Some(match t {
        ty::MATRIX2D => (Double, 4, 2, false),
        ty::MATRIX3D => (Double, 9, 3, false),
        ty::MATRIX4D => (Double, 16, 4, false),
        ty::QUATD => (Double, 4, 0, true),
        ty::QUATF => (Float, 4, 0, true),
        ty::QUATH => (Half, 4, 0, true),
        ty::VEC2D..=ty::VEC4I => {
            let k = usize::from(t - ty::VEC2D);
            let n = 2 + k / 4;
            let s = [Double, Float, Half, Int][k % 4];
            (s, n, 0, false)
        }
        _ => return None,
    })
}

fn scalar_size(s: Scalar) -> u64 {
    match s {
        Scalar::Half => 2,
        Scalar::Float | Scalar::Int => 4,
        Scalar::Double => 8,
    }
}

/// Components laid out as the text format writes them: matrices as rows, quaternions
/// `(w, x, y, z)` (the file holds `x, y, z, w`).
fn compose(mut c: Vec<f64>, rows: usize, quat: bool) -> Value {
    if quat {
        c.rotate_right(1);
    }
    if let Some(cols) = c.len().checked_div(rows) {
        return Value::Tuple(
            c.chunks(cols.max(1))
                .map(|r| Value::Tuple(r.iter().map(|&x| Value::Number(x)).collect()))
                .collect(),
        );
    }
    Value::Tuple(c.into_iter().map(Value::Number).collect())
}

fn bool_value(b: bool) -> Value {
    Value::Ident(if b { "true" } else { "false" }.into())
}

impl CrateFile<'_> {
    /// Decodes the value representation `bits`; `depth` counts enclosing values.
    pub(crate) fn value(&self, bits: u64, depth: usize) -> Result<Decoded, UsdError> {
        let rep = Rep::new(bits);
        if depth > MAX_VALUE_DEPTH {
            return Err(self.error(
                rep.payload,
                Problem::NestedTooDeep {
                    what: Nesting::Values,
                    limit: MAX_VALUE_DEPTH,
                },
            ));
        }
        if rep.array {
            return self.array_value(rep).map(|v| match v {
                Some(v) => Decoded::Value(v),
                None => Decoded::Unsupported(rep.ty),
            });
        }
        let low = rep.payload as u32;
        let v = match rep.ty {
            // Types that are always inlined: the payload is the value or an index.
            ty::BOOL => bool_value(low & 0xff != 0),
            ty::UCHAR => Value::Number(f64::from(low & 0xff)),
            ty::INT => Value::Number(f64::from(low as i32)),
            ty::UINT => Value::Number(f64::from(low)),
            ty::HALF => Value::Number(f64::from(coding::half_to_f32(low as u16))),
            ty::FLOAT => Value::Number(f64::from(f32::from_bits(low))),
            ty::STRING => Value::Str(self.string(rep.payload, low)?.to_string()),
            ty::TOKEN => Value::Str(self.token(rep.payload, low)?.to_string()),
            ty::ASSET_PATH => Value::Asset(self.token(rep.payload, low)?.to_string(), None),
            ty::SPECIFIER => Value::Ident(
                match low {
                    0 => "def",
                    1 => "over",
                    _ => "class",
                }
                .into(),
            ),
            ty::PERMISSION => Value::Ident(if low == 0 { "public" } else { "private" }.into()),
            ty::VARIABILITY => Value::Ident(if low == 0 { "varying" } else { "uniform" }.into()),
            ty::VALUE_BLOCK => Value::None,
            // Values that may be inlined when small (`crateValueInliners.h`).
            ty::DOUBLE if rep.inlined => Value::Number(f64::from(f32::from_bits(low))),
            ty::INT64 if rep.inlined => Value::Number(f64::from(low as i32)),
            ty::UINT64 if rep.inlined => Value::Number(f64::from(low)),
            ty::DICTIONARY if rep.inlined => Value::Dict(Vec::new()),
            t if rep.inlined && shape(t).is_some() => {
                let (_, n, rows, _) = shape(t).unwrap_or((Scalar::Int, 0, 0, false));
                let bytes = low.to_le_bytes();
                if rows > 0 {
                    // A diagonal matrix of small integers.
                    let mut c = vec![0.0; n];
                    for i in 0..rows {
                        if let Some(slot) = c.get_mut(i * rows + i) {
                            *slot = f64::from(bytes.get(i).copied().unwrap_or(0) as i8);
                        }
                    }
                    compose(c, rows, false)
                } else {
                    let c = (0..n)
                        .map(|i| f64::from(bytes.get(i).copied().unwrap_or(0) as i8))
                        .collect();
                    compose(c, 0, false)
                }
            }
            _ => return self.heap_value(rep, depth),
        };
        Ok(Decoded::Value(v))
    }

    /// A value stored at the payload's byte offset.
    fn heap_value(&self, rep: Rep, depth: usize) -> Result<Decoded, UsdError> {
        let c = &mut Cursor { pos: rep.payload };
        let v = match rep.ty {
            ty::DOUBLE | ty::TIME_CODE => Value::Number(self.f64(c)?),
            ty::INT64 => Value::Number(self.i64(c)? as f64),
            ty::UINT64 => Value::Number(self.u64(c)? as f64),
            t if shape(t).is_some() => self.element(t, c)?,
            ty::PATH_EXPRESSION => self.stream_string(c)?,
            ty::DICTIONARY => self.dictionary(c, depth)?,
            ty::TOKEN_LIST_OP
            | ty::STRING_LIST_OP
            | ty::PATH_LIST_OP
            | ty::REFERENCE_LIST_OP
            | ty::INT_LIST_OP
            | ty::INT64_LIST_OP
            | ty::UINT_LIST_OP
            | ty::UINT64_LIST_OP
            | ty::UNREGISTERED_VALUE_LIST_OP
            | ty::PAYLOAD_LIST_OP => return self.list_op(rep.ty, c, depth).map(Decoded::ListOp),
            ty::PATH_VECTOR | ty::TOKEN_VECTOR | ty::STRING_VECTOR => {
                let item = match rep.ty {
                    ty::PATH_VECTOR => ty::PATH_LIST_OP,
                    ty::TOKEN_VECTOR => ty::TOKEN_LIST_OP,
                    _ => ty::STRING_LIST_OP,
                };
                Value::List(self.items(item, c, depth)?)
            }
            ty::DOUBLE_VECTOR => {
                let n = self.count(c, true)?;
                Value::List(
                    (0..n)
                        .map(|_| self.f64(c).map(Value::Number))
                        .collect::<Result<_, _>>()?,
                )
            }
            ty::LAYER_OFFSET_VECTOR => {
                let n = self.count(c, true)?;
                let mut out = Vec::new();
                for _ in 0..n {
                    out.push(self.layer_offset(c)?);
                }
                Value::List(out)
            }
            ty::VARIANT_SELECTION_MAP => {
                let n = self.count(c, true)?;
                let mut out = Vec::new();
                for _ in 0..n {
                    let at = c.pos;
                    let key = self.u32(c)?;
                    let value = self.u32(c)?;
                    out.push((
                        self.string(at, key)?.to_string(),
                        Value::Str(self.string(at, value)?.to_string()),
                    ));
                }
                Value::Dict(out)
            }
            ty::TIME_SAMPLES => return self.time_samples(c, depth),
            ty::PAYLOAD => self.payload(c)?,
            ty::VALUE | ty::UNREGISTERED_VALUE => return self.vt_value(c, depth),
            ty::RELOCATES => {
                let n = self.count(c, true)?;
                let mut out = Vec::new();
                for _ in 0..n {
                    let at = c.pos;
                    let (a, b) = (self.u32(c)?, self.u32(c)?);
                    out.push(Value::Tuple(vec![
                        Value::Path(self.path_at(at, a)?.to_string()),
                        Value::Path(self.path_at(at, b)?.to_string()),
                    ]));
                }
                Value::List(out)
            }
            other => return Ok(Decoded::Unsupported(other)),
        };
        Ok(Decoded::Value(v))
    }

    /// A time-samples offset that points out of the file, at `at`.
    fn samples_offset_error(&self, at: u64) -> UsdError {
        let problem = Problem::OffsetOutOfFile {
            what: "time samples",
            offset: None,
        };
        self.error(at, problem)
    }

    /// A `VtValue` in a stream: an `i64` offset (from its own position) to a value
    /// representation, which is decoded; the cursor ends after that representation.
    fn vt_value(&self, c: &mut Cursor, depth: usize) -> Result<Decoded, UsdError> {
        let start = c.pos;
        let offset = self.i64(c)?;
        c.pos = start.checked_add_signed(offset).ok_or_else(|| {
            let problem = Problem::OffsetOutOfFile {
                what: "value",
                offset: Some(offset),
            };
            self.error(start, problem)
        })?;
        let bits = self.u64(c)?;
        self.value(bits, depth + 1)
    }

    /// A string written in a stream: a `u32` string index.
    fn stream_string(&self, c: &mut Cursor) -> Result<Value, UsdError> {
        let at = c.pos;
        let i = self.u32(c)?;
        Ok(Value::Str(self.string(at, i)?.to_string()))
    }

    fn layer_offset(&self, c: &mut Cursor) -> Result<Value, UsdError> {
        let offset = self.f64(c)?;
        let scale = self.f64(c)?;
        Ok(Value::Dict(vec![
            ("offset".into(), Value::Number(offset)),
            ("scale".into(), Value::Number(scale)),
        ]))
    }

    fn dictionary(&self, c: &mut Cursor, depth: usize) -> Result<Value, UsdError> {
        let n = self.count(c, true)?;
        let mut out = Vec::new();
        for _ in 0..n {
            let at = c.pos;
            let key = self.u32(c)?;
            let key = self.string(at, key)?.to_string();
            let value = match self.vt_value(c, depth)? {
                Decoded::Value(v) => v,
                Decoded::ListOp(ops) => Value::List(ops.into_iter().flat_map(|(_, v)| v).collect()),
                Decoded::Samples(_) | Decoded::Unsupported(_) => continue,
            };
            out.push((key, value));
        }
        Ok(Value::Dict(out))
    }

    fn payload(&self, c: &mut Cursor) -> Result<Value, UsdError> {
        let at = c.pos;
        let asset = self.u32(c)?;
        let prim = self.u32(c)?;
        if self.version_at_least(8) {
            self.layer_offset(c)?;
        }
        self.arc(at, asset, prim)
    }

    /// A reference or payload target: `@asset@</prim>`, or `</prim>` inside the layer.
    fn arc(&self, at: u64, asset: u32, prim: u32) -> Result<Value, UsdError> {
        let asset = self.string(at, asset)?.to_string();
        let prim = self.path_at(at, prim).ok().map(str::to_string);
        Ok(match (asset.is_empty(), prim) {
            (true, Some(p)) => Value::Path(p),
            (_, prim) => Value::Asset(asset, prim.filter(|p| !p.is_empty())),
        })
    }

    /// A list op's header byte and item vectors.
    fn list_op(
        &self,
        t: TypeId,
        c: &mut Cursor,
        depth: usize,
    ) -> Result<Vec<(ListOp, Vec<Value>)>, UsdError> {
        let bits = self.u8(c)?;
        // `_ListOpHeader` bits, and the order the vectors follow in.
        let is_explicit = bits & 1 != 0;
        let mut out = Vec::new();
        for (bit, op) in [
            (1 << 1, ListOp::Explicit),
            (1 << 2, ListOp::Add),
            (1 << 5, ListOp::Prepend),
            (1 << 6, ListOp::Append),
            (1 << 3, ListOp::Delete),
            (1 << 4, ListOp::Reorder),
        ] {
            if bits & bit != 0 {
                out.push((op, self.items(t, c, depth)?));
            }
        }
        if is_explicit && !out.iter().any(|(op, _)| *op == ListOp::Explicit) {
            out.insert(0, (ListOp::Explicit, Vec::new()));
        }
        Ok(out)
    }

    /// A `u64` count and that many items of a list op's item type.
    fn items(&self, t: TypeId, c: &mut Cursor, depth: usize) -> Result<Vec<Value>, UsdError> {
        let n = self.count(c, true)?;
        let mut out = Vec::with_capacity(n.min(1 << 16));
        for _ in 0..n {
            let at = c.pos;
            let v = match t {
                ty::TOKEN_LIST_OP => {
                    let i = self.u32(c)?;
                    Value::Str(self.token(at, i)?.to_string())
                }
                ty::STRING_LIST_OP => self.stream_string(c)?,
                ty::PATH_LIST_OP => {
                    let i = self.u32(c)?;
                    Value::Path(self.path_at(at, i)?.to_string())
                }
                ty::INT_LIST_OP => Value::Number(f64::from(self.i32(c)?)),
                ty::UINT_LIST_OP => Value::Number(f64::from(self.u32(c)?)),
                ty::INT64_LIST_OP => Value::Number(self.i64(c)? as f64),
                ty::UINT64_LIST_OP => Value::Number(self.u64(c)? as f64),
                ty::REFERENCE_LIST_OP => {
                    let asset = self.u32(c)?;
                    let prim = self.u32(c)?;
                    self.layer_offset(c)?;
                    self.dictionary(c, depth + 1)?;
                    self.arc(at, asset, prim)?
                }
                ty::PAYLOAD_LIST_OP => self.payload(c)?,
                _ => match self.vt_value(c, depth)? {
                    Decoded::Value(v) => v,
                    _ => Value::None,
                },
            };
            out.push(v);
        }
        Ok(out)
    }

    fn time_samples(&self, c: &mut Cursor, depth: usize) -> Result<Decoded, UsdError> {
        // An offset to the times' representation, then an offset to the values'.
        let start = c.pos;
        let jump = self.i64(c)?;
        c.pos = start
            .checked_add_signed(jump)
            .ok_or_else(|| self.samples_offset_error(start))?;
        let times_at = c.pos;
        let times = match self.value(self.u64(c)?, depth + 1)? {
            Decoded::Value(Value::List(t)) => t,
            Decoded::Value(Value::Number(t)) => vec![Value::Number(t)],
            _ => return Err(self.error(times_at, CrateProblem::SampleTimes("doubles"))),
        };
        let start = c.pos;
        let jump = self.i64(c)?;
        c.pos = start
            .checked_add_signed(jump)
            .ok_or_else(|| self.samples_offset_error(start))?;
        let at = c.pos;
        let n = self.count(c, true)?;
        if n != times.len() {
            return Err(self.error(
                at,
                CrateProblem::SampleValues {
                    values: n,
                    times: times.len(),
                },
            ));
        }
        let mut out = Vec::with_capacity(n);
        for time in times {
            let Value::Number(t) = time else {
                return Err(self.error(times_at, CrateProblem::SampleTimes("numbers")));
            };
            let bits = self.u64(c)?;
            let v = match self.value(bits, depth + 1)? {
                Decoded::Value(v) => v,
                Decoded::ListOp(ops) => Value::List(ops.into_iter().flat_map(|(_, v)| v).collect()),
                Decoded::Samples(_) | Decoded::Unsupported(_) => Value::None,
            };
            out.push((t, v));
        }
        Ok(Decoded::Samples(out))
    }

    /// One element of a fixed-size type read from a stream.
    fn element(&self, t: TypeId, c: &mut Cursor) -> Result<Value, UsdError> {
        Ok(match t {
            ty::BOOL => bool_value(self.u8(c)? != 0),
            ty::UCHAR => Value::Number(f64::from(self.u8(c)?)),
            ty::INT => Value::Number(f64::from(self.i32(c)?)),
            ty::UINT => Value::Number(f64::from(self.u32(c)?)),
            ty::INT64 => Value::Number(self.i64(c)? as f64),
            ty::UINT64 => Value::Number(self.u64(c)? as f64),
            ty::HALF => Value::Number(f64::from(coding::half_to_f32(self.u16(c)?))),
            ty::FLOAT => Value::Number(f64::from(self.f32(c)?)),
            ty::DOUBLE | ty::TIME_CODE => Value::Number(self.f64(c)?),
            ty::STRING | ty::PATH_EXPRESSION => self.stream_string(c)?,
            ty::TOKEN => {
                let at = c.pos;
                let i = self.u32(c)?;
                Value::Str(self.token(at, i)?.to_string())
            }
            ty::ASSET_PATH => {
                let Value::Str(s) = self.stream_string(c)? else {
                    return Ok(Value::None);
                };
                Value::Asset(s, None)
            }
            t => {
                let Some((s, n, rows, quat)) = shape(t) else {
                    return Err(self.error(c.pos, CrateProblem::NoElements(t)));
                };
                let mut comps = Vec::with_capacity(n);
                for _ in 0..n {
                    comps.push(self.scalar(s, c)?);
                }
                compose(comps, rows, quat)
            }
        })
    }

    fn scalar(&self, s: Scalar, c: &mut Cursor) -> Result<f64, UsdError> {
        Ok(match s {
            Scalar::Half => f64::from(coding::half_to_f32(self.u16(c)?)),
            Scalar::Float => f64::from(self.f32(c)?),
            Scalar::Double => self.f64(c)?,
            Scalar::Int => f64::from(self.i32(c)?),
        })
    }

    /// Bytes per element of an array type, when it has a fixed size.
    fn element_size(t: TypeId) -> Option<u64> {
        Some(match t {
            ty::BOOL | ty::UCHAR => 1,
            ty::HALF => 2,
            ty::INT | ty::UINT | ty::FLOAT | ty::STRING | ty::TOKEN | ty::ASSET_PATH => 4,
            ty::PATH_EXPRESSION => 4,
            ty::INT64 | ty::UINT64 | ty::DOUBLE | ty::TIME_CODE => 8,
            t => {
                let (s, n, _, _) = shape(t)?;
                scalar_size(s) * n as u64
            }
        })
    }

    /// An array value; `None` for an element type this reader does not know.
    fn array_value(&self, rep: Rep) -> Result<Option<Value>, UsdError> {
        let Some(size) = Self::element_size(rep.ty) else {
            return Ok(None);
        };
        if rep.payload == 0 {
            return Ok(Some(Value::List(Vec::new())));
        }
        let c = &mut Cursor { pos: rep.payload };
        if !self.version_at_least(5) {
            // Versions before 0.5.0 write a (rank) shape word first.
            self.u32(c)?;
        }
        let at = c.pos;
        let n = self.count(c, self.version_at_least(7))?;
        let is_int = matches!(rep.ty, ty::INT | ty::UINT | ty::INT64 | ty::UINT64);
        let is_float = matches!(rep.ty, ty::HALF | ty::FLOAT | ty::DOUBLE);
        let compressed = rep.compressed && n >= MIN_COMPRESSED_ARRAY;
        if compressed && is_int && self.version_at_least(5) {
            let width = if matches!(rep.ty, ty::INT64 | ty::UINT64) {
                Width::W64
            } else {
                Width::W32
            };
            let ints = self.compressed_ints(c, n, width)?;
            let items = ints
                .into_iter()
                .map(|i| {
                    Value::Number(match rep.ty {
                        ty::UINT => f64::from(i as u32),
                        ty::UINT64 => i as u64 as f64,
                        _ => i as f64,
                    })
                })
                .collect();
            return Ok(Some(Value::List(items)));
        }
        if compressed && is_float && self.version_at_least(6) {
            let code = self.u8(c)?;
            let items = match code {
                b'i' => self
                    .compressed_ints(c, n, Width::W32)?
                    .into_iter()
                    .map(|i| Value::Number(f64::from(i as i32)))
                    .collect(),
                b't' => {
                    let lut_n = self.count(c, false)?;
                    let mut lut = Vec::with_capacity(lut_n);
                    for _ in 0..lut_n {
                        lut.push(self.element(rep.ty, c)?);
                    }
                    let index_at = c.pos;
                    let indices = self.compressed_ints(c, n, Width::W32)?;
                    indices
                        .into_iter()
                        .map(|i| {
                            lut.get(i as u32 as usize).cloned().ok_or_else(|| {
                                self.index_error(index_at, "lookup", i, Some(lut_n), "values")
                            })
                        })
                        .collect::<Result<_, _>>()?
                }
                other => return Err(self.error(at, CrateProblem::FloatCoding(char::from(other)))),
            };
            return Ok(Some(Value::List(items)));
        }
        // Uncompressed: check the whole extent first, so a huge count fails at once.
        let total = size.checked_mul(n as u64).ok_or_else(|| {
            let too_many = Problem::TooMany {
                what: "elements",
                count: Some(n as u64),
            };
            self.error(at, too_many)
        })?;
        if c.pos.saturating_add(total) > self.data.len() as u64 {
            return Err(self.truncated(c.pos, total, &format!("an array of {n} elements")));
        }
        if let Some((_, comps, _, _)) = shape(rep.ty) {
            self.spend(at, (n * comps) as u64)?;
        }
        let mut items = Vec::with_capacity(n);
        for _ in 0..n {
            items.push(self.element(rep.ty, c)?);
        }
        Ok(Some(Value::List(items)))
    }
}
