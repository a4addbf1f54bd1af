//! Text values written as crate value representations, typed by the attribute's value
//! type name (`point3f[]`) or by the metadata field's type in `Sdf`'s schema.
//!
//! Type numbers are `crateDataTypes.h`'s; scalars of at most 4 bytes, tokens, strings,
//! asset paths and enums are inlined in the representation as `crateFile.cpp` does;
//! everything else is written to the heap, `int[]`/`uint[]` of 16 or more elements with
//! integer coding as usd-core writes them, other arrays uncompressed (which every crate
//! reader reads).

use super::tables::{put_u64, Tables};
use crate::layer::{ListOp, Value};

/// Crate type numbers used by the writer.
pub(crate) mod ty {
    pub const BOOL: u8 = 1;
    pub const UCHAR: u8 = 2;
    pub const INT: u8 = 3;
    pub const UINT: u8 = 4;
    pub const INT64: u8 = 5;
    pub const UINT64: u8 = 6;
    pub const HALF: u8 = 7;
    pub const FLOAT: u8 = 8;
    pub const DOUBLE: u8 = 9;
    pub const STRING: u8 = 10;
    pub const TOKEN: u8 = 11;
    pub const ASSET_PATH: u8 = 12;
    pub const MATRIX2D: u8 = 13;
    pub const MATRIX3D: u8 = 14;
    pub const MATRIX4D: u8 = 15;
    pub const QUATD: u8 = 16;
    pub const QUATF: u8 = 17;
    pub const QUATH: u8 = 18;
    pub const VEC2D: u8 = 19;
    pub const DICTIONARY: u8 = 31;
    pub const TOKEN_LIST_OP: u8 = 32;
    pub const STRING_LIST_OP: u8 = 33;
    pub const PATH_LIST_OP: u8 = 34;
    pub const PATH_VECTOR: u8 = 40;
    pub const TOKEN_VECTOR: u8 = 41;
    pub const SPECIFIER: u8 = 42;
    pub const VARIABILITY: u8 = 44;
    pub const VARIANT_SELECTION_MAP: u8 = 45;
    pub const TIME_SAMPLES: u8 = 46;
    pub const DOUBLE_VECTOR: u8 = 48;
    pub const STRING_VECTOR: u8 = 50;
    pub const VALUE_BLOCK: u8 = 51;
    pub const TIME_CODE: u8 = 56;
}

/// Arrays of at least this many integers are written compressed (`MinCompressedArraySize`).
const MIN_COMPRESSED_ARRAY: usize = 16;

/// The "compressed" flag of a value representation.
const COMPRESSED: u64 = 1 << 61;

/// A value representation: type, array/inlined flags and a 48-bit payload.
pub(crate) fn rep(t: u8, array: bool, inlined: bool, payload: u64) -> u64 {
    (u64::from(t) << 48)
        | (u64::from(array) << 63)
        | (u64::from(inlined) << 62)
        | (payload & ((1 << 48) - 1))
}

/// The crate type of an attribute value type name (without `[]`); `None` for unknown
/// names.
pub(crate) fn value_type(name: &str) -> Option<u8> {
    Some(match name {
        "bool" => ty::BOOL,
        "uchar" => ty::UCHAR,
        "int" => ty::INT,
        "uint" => ty::UINT,
        "int64" => ty::INT64,
        "uint64" => ty::UINT64,
        "half" => ty::HALF,
        "float" => ty::FLOAT,
        "double" => ty::DOUBLE,
        "timecode" => ty::TIME_CODE,
        "string" => ty::STRING,
        "token" => ty::TOKEN,
        "asset" => ty::ASSET_PATH,
        "matrix2d" => ty::MATRIX2D,
        "matrix3d" => ty::MATRIX3D,
        "matrix4d" | "frame4d" => ty::MATRIX4D,
        "quatd" => ty::QUATD,
        "quatf" => ty::QUATF,
        "quath" => ty::QUATH,
        _ => return vector_type(name),
    })
}

/// `double2`..`int4`, and the role types `point3f`, `normal3d`, `color4h`, `texCoord2f`...
fn vector_type(name: &str) -> Option<u8> {
    let scalar_of = |s: &str| {
        ["double", "float", "half", "int"]
            .iter()
            .position(|&x| x == s)
    };
    let digit = name.find(|c: char| c.is_ascii_digit())?;
    let (base, rest) = name.split_at(digit);
    let dim = rest.get(..1)?.parse::<u8>().ok()?;
    let scalar = match (scalar_of(base), rest.get(1..)?) {
        (Some(k), "") => k,
        (None, suffix) if ["point", "normal", "vector", "color", "texCoord"].contains(&base) => {
            ["d", "f", "h"].iter().position(|&x| x == suffix)?
        }
        _ => return None,
    };
    (2..=4)
        .contains(&dim)
        .then(|| ty::VEC2D + (dim - 2) * 4 + scalar as u8)
}

/// Scalar kind and component count of vector, matrix and quaternion types.
fn components(t: u8) -> Option<(u8, usize)> {
    Some(match t {
        ty::MATRIX2D => (ty::DOUBLE, 4),
        ty::MATRIX3D => (ty::DOUBLE, 9),
        ty::MATRIX4D => (ty::DOUBLE, 16),
        ty::QUATD => (ty::DOUBLE, 4),
        ty::QUATF => (ty::FLOAT, 4),
        ty::QUATH => (ty::HALF, 4),
        t if (ty::VEC2D..=30).contains(&t) => {
            let k = t - ty::VEC2D;
            let scalar = [ty::DOUBLE, ty::FLOAT, ty::HALF, ty::INT][usize::from(k % 4)];
            (scalar, 2 + usize::from(k / 4))
        }
        _ => return None,
    })
}

/// Why a value cannot be written (the caller adds the location).
pub(crate) type ValueError = String;

/// The numbers of a value, flattened (tuples and rows), in the text's order.
fn flatten(v: &Value, out: &mut Vec<f64>) -> Result<(), ValueError> {
    match v {
        Value::Number(x) => out.push(*x),
        Value::Ident(s) if s == "true" => out.push(1.0),
        Value::Ident(s) if s == "false" => out.push(0.0),
        Value::Tuple(items) => {
            for i in items {
                flatten(i, out)?;
            }
        }
        other => return Err(format!("expected a number or a tuple, found {other:?}")),
    }
    Ok(())
}

fn text(v: &Value) -> Result<&str, ValueError> {
    match v {
        Value::Str(s) | Value::Ident(s) | Value::Asset(s, None) => Ok(s),
        other => Err(format!("expected a string, found {other:?}")),
    }
}

impl Tables {
    /// Writes one element of type `t` to `buf` (arrays and non-inlined values).
    fn element(&mut self, t: u8, v: &Value, buf: &mut Vec<u8>) -> Result<(), ValueError> {
        match t {
            ty::STRING => buf.extend_from_slice(&self.string(text(v)?).to_le_bytes()),
            ty::ASSET_PATH => buf.extend_from_slice(&self.string(text(v)?).to_le_bytes()),
            ty::TOKEN => buf.extend_from_slice(&self.token(text(v)?).to_le_bytes()),
            _ => {
                let mut n = Vec::new();
                flatten(v, &mut n)?;
                let (scalar, count) = components(t).unwrap_or((t, 1));
                if n.len() != count {
                    return Err(format!("{} numbers where {count} are needed", n.len()));
                }
                if matches!(t, ty::QUATD | ty::QUATF | ty::QUATH) {
                    // Text (w, x, y, z), file (x, y, z, w).
                    n.rotate_left(1);
                }
                for x in n {
                    match scalar {
                        ty::BOOL | ty::UCHAR => buf.push(x as u8),
                        ty::INT => buf.extend_from_slice(&(x as i32).to_le_bytes()),
                        ty::UINT => buf.extend_from_slice(&(x as u32).to_le_bytes()),
                        ty::INT64 => buf.extend_from_slice(&(x as i64).to_le_bytes()),
                        ty::UINT64 => buf.extend_from_slice(&(x as u64).to_le_bytes()),
                        ty::HALF => buf
                            .extend_from_slice(&super::encode::f32_to_half(x as f32).to_le_bytes()),
                        ty::FLOAT => buf.extend_from_slice(&(x as f32).to_le_bytes()),
                        _ => buf.extend_from_slice(&x.to_le_bytes()),
                    }
                }
            }
        }
        Ok(())
    }

    /// Appends `bytes` to the heap (8-byte aligned) and returns their offset.
    fn heap(&mut self, bytes: &[u8]) -> u64 {
        self.align(8);
        let at = self.out.len() as u64;
        self.out.extend_from_slice(bytes);
        at
    }

    /// An attribute value of type name `type_name` (`float3[]`, `token`, ...).
    pub(crate) fn attr_value(&mut self, type_name: &str, v: &Value) -> Result<u64, ValueError> {
        if *v == Value::None {
            return Ok(rep(ty::VALUE_BLOCK, false, true, 0));
        }
        let (base, array) = match type_name.strip_suffix("[]") {
            Some(b) => (b, true),
            None => (type_name, false),
        };
        let t = value_type(base).ok_or_else(|| format!("unknown value type {type_name:?}"))?;
        if array {
            let Value::List(items) = v else {
                return Err(format!("expected a list for {type_name}, found {v:?}"));
            };
            if items.is_empty() {
                return Ok(rep(t, true, false, 0));
            }
            if matches!(t, ty::INT | ty::UINT) && items.len() >= MIN_COMPRESSED_ARRAY {
                // Integer coding, as `crateFile.cpp` compresses `int[]` (and `uint[]`) of 16
                // elements or more: the count, then the compressed integers.
                let mut ints = Vec::with_capacity(items.len());
                for item in items {
                    let mut n = Vec::new();
                    flatten(item, &mut n)?;
                    let [x] = n[..] else {
                        return Err(format!("expected a number, found {item:?}"));
                    };
                    ints.push(if t == ty::INT {
                        x as i32
                    } else {
                        x as u32 as i32
                    });
                }
                let packed = super::encode::compress_ints(&ints);
                let mut buf = Vec::new();
                put_u64(&mut buf, items.len() as u64);
                put_u64(&mut buf, packed.len() as u64);
                buf.extend_from_slice(&packed);
                let at = self.heap(&buf);
                return Ok(rep(t, true, false, at) | COMPRESSED);
            }
            let mut buf = Vec::new();
            put_u64(&mut buf, items.len() as u64);
            for item in items {
                self.element(t, item, &mut buf)?;
            }
            let at = self.heap(&buf);
            return Ok(rep(t, true, false, at));
        }
        self.scalar(t, v)
    }

    /// A single value of crate type `t`: inlined when `crateFile.cpp` always inlines the
    /// type, else on the heap.
    pub(crate) fn scalar(&mut self, t: u8, v: &Value) -> Result<u64, ValueError> {
        let inline = |x: u32| Ok(rep(t, false, true, u64::from(x)));
        match t {
            ty::BOOL | ty::UCHAR | ty::INT | ty::UINT | ty::FLOAT | ty::HALF => {
                let mut n = Vec::new();
                flatten(v, &mut n)?;
                let [x] = n[..] else {
                    return Err(format!("expected one number, found {v:?}"));
                };
                inline(match t {
                    ty::BOOL => u32::from(x != 0.0),
                    ty::UCHAR => u32::from(x as u8),
                    ty::INT => x as i32 as u32,
                    ty::UINT => x as u32,
                    ty::HALF => u32::from(super::encode::f32_to_half(x as f32)),
                    _ => (x as f32).to_bits(),
                })
            }
            ty::STRING => inline(self.string(text(v)?)),
            ty::TOKEN | ty::ASSET_PATH => inline(self.token(text(v)?)),
            _ => {
                let mut buf = Vec::new();
                self.element(t, v, &mut buf)?;
                let at = self.heap(&buf);
                Ok(rep(t, false, false, at))
            }
        }
    }

    /// A token vector (`primChildren`, `properties`, ...).
    pub(crate) fn token_vector(&mut self, names: &[&str]) -> u64 {
        let mut buf = Vec::new();
        put_u64(&mut buf, names.len() as u64);
        for n in names {
            buf.extend_from_slice(&self.token(n).to_le_bytes());
        }
        let at = self.heap(&buf);
        rep(ty::TOKEN_VECTOR, false, false, at)
    }

    /// A path vector (`targetChildren`, `connectionChildren`).
    pub(crate) fn path_vector(&mut self, paths: &[String]) -> u64 {
        let mut buf = Vec::new();
        put_u64(&mut buf, paths.len() as u64);
        for p in paths {
            buf.extend_from_slice(&self.path(p).to_le_bytes());
        }
        let at = self.heap(&buf);
        rep(ty::PATH_VECTOR, false, false, at)
    }

    /// A list op of tokens, strings or paths: its operations in the text's order.
    pub(crate) fn list_op(
        &mut self,
        t: u8,
        ops: &[(ListOp, Vec<Value>)],
    ) -> Result<u64, ValueError> {
        let bit = |op: ListOp| match op {
            ListOp::Explicit => 1 << 1,
            ListOp::Add => 1 << 2,
            ListOp::Delete => 1 << 3,
            ListOp::Reorder => 1 << 4,
            ListOp::Prepend => 1 << 5,
            ListOp::Append => 1 << 6,
        };
        let mut header = 0_u8;
        for (op, items) in ops {
            if *op == ListOp::Explicit {
                header |= 1;
            }
            if !items.is_empty() {
                header |= bit(*op);
            }
        }
        let mut buf = vec![header];
        // The order `crateFile.cpp` writes the vectors in.
        for op in [
            ListOp::Explicit,
            ListOp::Add,
            ListOp::Prepend,
            ListOp::Append,
            ListOp::Delete,
            ListOp::Reorder,
        ] {
            let Some((_, items)) = ops.iter().find(|(o, i)| *o == op && !i.is_empty()) else {
                continue;
            };
            put_u64(&mut buf, items.len() as u64);
            for item in items {
                let index = match (t, item) {
                    (ty::PATH_LIST_OP, Value::Path(p)) => self.path(p),
                    (ty::STRING_LIST_OP, v) => self.string(text(v)?),
                    (_, v) => self.token(text(v)?),
                };
                buf.extend_from_slice(&index.to_le_bytes());
            }
        }
        let at = self.heap(&buf);
        Ok(rep(t, false, false, at))
    }

    /// A dictionary; entry types are inferred from the text values (the parser does not
    /// keep the declared types): numbers are doubles, strings strings, `true`/`false`
    /// bools, nested dictionaries dictionaries, lists of numbers `double[]`, lists of
    /// strings `string[]`.
    pub(crate) fn dictionary(&mut self, entries: &[(String, Value)]) -> Result<u64, ValueError> {
        let mut buf = Vec::new();
        put_u64(&mut buf, entries.len() as u64);
        for (key, value) in entries {
            buf.extend_from_slice(&self.string(key).to_le_bytes());
            // A `VtValue`: an offset (from its own position) to its representation, which
            // follows the value's own heap data (here: none inside this buffer).
            let value_rep = match value {
                Value::Number(_) => self.scalar(ty::DOUBLE, value)?,
                Value::Ident(s) if s == "true" || s == "false" => self.scalar(ty::BOOL, value)?,
                Value::Str(_) | Value::Ident(_) => self.scalar(ty::STRING, value)?,
                Value::Asset(..) => self.scalar(ty::ASSET_PATH, value)?,
                Value::Dict(inner) => self.dictionary(inner)?,
                Value::List(items) if items.iter().all(|i| matches!(i, Value::Number(_))) => {
                    self.attr_value("double[]", value)?
                }
                Value::List(_) => self.attr_value("string[]", value)?,
                other => return Err(format!("a dictionary value {other:?}")),
            };
            put_u64(&mut buf, 8);
            buf.extend_from_slice(&value_rep.to_le_bytes());
        }
        let at = self.heap(&buf);
        Ok(rep(ty::DICTIONARY, false, false, at))
    }

    /// A variant selection map (`variants = { string set = "v" }`).
    pub(crate) fn variant_selection(
        &mut self,
        entries: &[(String, Value)],
    ) -> Result<u64, ValueError> {
        let mut buf = Vec::new();
        put_u64(&mut buf, entries.len() as u64);
        for (key, value) in entries {
            buf.extend_from_slice(&self.string(key).to_le_bytes());
            buf.extend_from_slice(&self.string(text(value)?).to_le_bytes());
        }
        let at = self.heap(&buf);
        Ok(rep(ty::VARIANT_SELECTION_MAP, false, false, at))
    }

    /// Time samples: the times (a double vector) and one representation per value.
    pub(crate) fn time_samples(
        &mut self,
        type_name: &str,
        samples: &[(f64, Value)],
    ) -> Result<u64, ValueError> {
        // Values first (each possibly on the heap), then the samples record.
        let mut reps = Vec::with_capacity(samples.len());
        for (_, v) in samples {
            reps.push(self.attr_value(type_name, v)?);
        }
        let mut times = Vec::new();
        put_u64(&mut times, samples.len() as u64);
        for (t, _) in samples {
            times.extend_from_slice(&t.to_le_bytes());
        }
        let times_at = self.heap(&times);
        let times_rep = rep(ty::DOUBLE_VECTOR, false, false, times_at);
        // [offset to times rep = 8][times rep][offset to values = 8][count][reps]
        let mut buf = Vec::new();
        put_u64(&mut buf, 8);
        buf.extend_from_slice(&times_rep.to_le_bytes());
        put_u64(&mut buf, 8);
        put_u64(&mut buf, reps.len() as u64);
        for r in reps {
            buf.extend_from_slice(&r.to_le_bytes());
        }
        let at = self.heap(&buf);
        Ok(rep(ty::TIME_SAMPLES, false, false, at))
    }
}
