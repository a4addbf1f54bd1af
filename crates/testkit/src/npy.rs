//! Reading `.npy` arrays and `.npz` archives (numpy's `lib/format.py` documents them).

/// Reads a `.npz` written by `rigport eval`: name -> (shape, f64 values or strings).
///
/// # Panics
/// The file is missing or not an `.npz` of the dtypes [`parse_npy`] reads.
pub fn read_npz(path: &std::path::Path) -> std::collections::BTreeMap<String, NpyArray> {
    let bytes = std::fs::read(path).expect("npz exists");
    let mut zip = zip::ZipArchive::new(std::io::Cursor::new(bytes)).expect("npz is a zip");
    let mut out = std::collections::BTreeMap::new();
    for i in 0..zip.len() {
        use std::io::Read;
        let mut f = zip.by_index(i).expect("entry");
        let name = f.name().trim_end_matches(".npy").to_string();
        let mut data = Vec::new();
        f.read_to_end(&mut data).expect("read entry");
        out.insert(name, parse_npy(&data));
    }
    out
}

/// One `.npy` array.
#[derive(Debug)]
pub struct NpyArray {
    /// Its shape (C order).
    pub shape: Vec<usize>,
    /// Its numbers (`<f4`, `<i4`), as f64.
    pub numbers: Vec<f64>,
    /// Its strings (`<U n`).
    pub strings: Vec<String>,
}

/// Reads one `.npy` file (see [`parse_npy`]).
pub fn read_npy(path: &std::path::Path) -> NpyArray {
    parse_npy(&std::fs::read(path).expect("npy exists"))
}

/// Parses one `.npy` file (format 1.0; `<f4`, `<i4` or `<U n`).
///
/// # Panics
/// Not an `.npy` of those dtypes.
pub fn parse_npy(data: &[u8]) -> NpyArray {
    assert_eq!(&data[..6], b"\x93NUMPY");
    let hlen = u16::from_le_bytes([data[8], data[9]]) as usize;
    let header = std::str::from_utf8(&data[10..10 + hlen]).expect("ascii header");
    let body = &data[10 + hlen..];
    let descr = header
        .split("'descr': '")
        .nth(1)
        .expect("descr")
        .split('\'')
        .next()
        .expect("descr");
    let shape_text = header
        .split("'shape': (")
        .nth(1)
        .expect("shape")
        .split(')')
        .next()
        .expect("shape");
    let shape: Vec<usize> = shape_text
        .split(',')
        .filter(|s| !s.trim().is_empty())
        .map(|s| s.trim().parse().expect("dim"))
        .collect();
    let mut arr = NpyArray {
        shape,
        numbers: Vec::new(),
        strings: Vec::new(),
    };
    match descr {
        "<f4" => {
            arr.numbers = body
                .chunks_exact(4)
                .map(|c| f32::from_le_bytes([c[0], c[1], c[2], c[3]]) as f64)
                .collect()
        }
        "<i4" => {
            arr.numbers = body
                .chunks_exact(4)
                .map(|c| i32::from_le_bytes([c[0], c[1], c[2], c[3]]) as f64)
                .collect()
        }
        d if d.starts_with("<U") => {
            let width: usize = d[2..].parse().expect("width");
            arr.strings = body
                .chunks_exact(4 * width)
                .map(|c| {
                    c.chunks_exact(4)
                        .map(|b| u32::from_le_bytes([b[0], b[1], b[2], b[3]]))
                        .take_while(|&u| u != 0)
                        .filter_map(char::from_u32)
                        .collect()
                })
                .collect()
        }
        other => panic!("unexpected dtype {other}"),
    }
    arr
}
