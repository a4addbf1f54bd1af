//! A minimal `.npz` writer (a zip of `.npy` arrays, as `numpy.savez` writes), and the
//! arrays of a `rigport eval` dump ([`EvalDump`]).
//!
//! NPY format 1.0: magic, version, a little-endian u16 header length, a Python-literal
//! header dict padded with spaces to a multiple of 64 bytes and ending in `\n`, then the raw
//! C-order data (numpy's `lib/format.py` documents it).

/// The arrays of an eval dump as a user reads them (the CLI's `eval` help shows it).
pub const EVAL_DUMP_FORMAT: &str =
    "The .npz holds positions, rest_positions (V x 3, source vertex order), joint_names, \
    joint_world and skin_matrices (J x 4 x 4, column vectors: p' = M p), \
    influence_joints and influence_weights (V x K, zero-padded), skinning ([\"lbs\"] or \
    [\"dqs\"]).\n\n\
    Without a pose file, a rig with clips plays one (the first unless one is named) and the \
    arrays that change get a leading frame axis: times (F, seconds), positions \
    (F x V x 3), joint_world and skin_matrices (F x J x 4 x 4).";

use std::cell::Cell;
use std::io::{self, Cursor, Seek, Write};

mod dump;
mod spill;

pub use dump::{influence_row, padded, EvalArrays, EvalDump};
pub use spill::SPILL_LIMIT;

use spill::Spill;

/// One array's element type and bytes.
#[derive(Clone, Debug, PartialEq)]
pub enum Data {
    /// little-endian f32
    F32(Vec<f32>),
    /// little-endian i32
    I32(Vec<i32>),
    /// fixed-width unicode strings (numpy `<U n`)
    Str(Vec<String>),
}

/// Builds an `.npz` file; arrays are stored uncompressed, in insertion order, with a fixed
/// timestamp so the bytes are deterministic. [`NpzWriter::finish`] returns the bytes,
/// [`NpzWriter::write_to`] streams them into a file.
///
/// ```
/// use rigport_export::npz::{Data, NpzWriter};
///
/// let mut npz = NpzWriter::default();
/// npz.add("times", &[2], Data::F32(vec![0.0, 0.5]));
/// npz.add("names", &[1], Data::Str(vec!["hips".into()]));
/// let bytes = npz.finish()?;
/// assert_eq!(&bytes[..4], b"PK\x03\x04");
/// # Ok::<(), std::io::Error>(())
/// ```
#[derive(Debug, Default)]
pub struct NpzWriter {
    arrays: Vec<(String, Vec<usize>, Body)>,
}

/// An array's bytes: values, or little-endian f32 bytes appended to a [`Spill`].
#[derive(Debug)]
enum Body {
    Data(Data),
    F32Spill(Spill),
}

impl NpzWriter {
    /// Adds an array of the given shape (C order). The product of `shape` must equal the
    /// element count; the caller guarantees it.
    pub fn add(&mut self, name: &str, shape: &[usize], data: Data) {
        self.arrays
            .push((name.to_string(), shape.to_vec(), Body::Data(data)));
    }

    /// Adds an f32 array whose bytes are in `spill`.
    fn add_spill(&mut self, name: &str, shape: &[usize], spill: Spill) {
        self.arrays
            .push((name.to_string(), shape.to_vec(), Body::F32Spill(spill)));
    }

    /// The `.npz` bytes.
    ///
    /// # Errors
    /// The zip writer fails (in memory: only for an archive too large for zip64).
    pub fn finish(self) -> io::Result<Vec<u8>> {
        Ok(self.write_to(Cursor::new(Vec::new()))?.into_inner())
    }

    /// Writes the `.npz` to `sink` from its current position and returns it; the bytes are
    /// those of [`NpzWriter::finish`]. Each array is copied in turn (a spilled one from its
    /// temporary file), so memory does not grow with the arrays' sizes.
    ///
    /// # Errors
    /// Writing or seeking `sink`; reading a spilled array back.
    pub fn write_to<W: Write + Seek>(self, sink: W) -> io::Result<W> {
        let abandoned = Cell::new(false);
        let mut zip = zip::ZipWriter::new(Abandonable::new(sink, &abandoned)?);
        if let Err(e) = self.write_entries(&mut zip) {
            // The zip writer's drop would finish the archive into a sink that just failed,
            // and print that failure to stderr: the caller reports the error once.
            abandoned.set(true);
            return Err(e);
        }
        Ok(zip.finish().map_err(io_error)?.inner)
    }

    /// Writes every array as an entry of `zip`.
    fn write_entries<W: Write + Seek>(self, zip: &mut zip::ZipWriter<W>) -> io::Result<()> {
        for (name, shape, body) in self.arrays {
            match body {
                Body::Data(data) => {
                    let (descr, bytes) = npy_body(&data);
                    let header = npy_header(&shape, &descr);
                    start_entry(zip, &name, &header, bytes.len() as u64)?;
                    zip.write_all(&bytes)?;
                }
                Body::F32Spill(spill) => {
                    start_entry(zip, &name, &npy_header(&shape, "<f4"), spill.len())?;
                    spill.copy_to(zip)?;
                }
            }
        }
        Ok(())
    }
}

/// A sink whose writes and seeks do nothing once `abandoned` is set (after a failed
/// write: the output is discarded anyway), while still answering positions as if they
/// had happened, so that the zip writer's own bookkeeping stays consistent.
struct Abandonable<'a, W> {
    inner: W,
    abandoned: &'a Cell<bool>,
    /// The position after the last write or seek.
    pos: u64,
    /// The furthest position written.
    end: u64,
}

impl<'a, W: Seek> Abandonable<'a, W> {
    fn new(mut inner: W, abandoned: &'a Cell<bool>) -> io::Result<Self> {
        let pos = inner.stream_position()?;
        Ok(Self {
            inner,
            abandoned,
            pos,
            end: pos,
        })
    }
}

impl<W: Write> Write for Abandonable<'_, W> {
    fn write(&mut self, buf: &[u8]) -> io::Result<usize> {
        let n = if self.abandoned.get() {
            buf.len()
        } else {
            self.inner.write(buf)?
        };
        self.pos += n as u64;
        self.end = self.end.max(self.pos);
        Ok(n)
    }

    fn flush(&mut self) -> io::Result<()> {
        if self.abandoned.get() {
            return Ok(());
        }
        self.inner.flush()
    }
}

impl<W: Seek> Seek for Abandonable<'_, W> {
    fn seek(&mut self, to: io::SeekFrom) -> io::Result<u64> {
        self.pos = if self.abandoned.get() {
            match to {
                io::SeekFrom::Start(n) => n,
                io::SeekFrom::Current(d) => self.pos.saturating_add_signed(d),
                io::SeekFrom::End(d) => self.end.saturating_add_signed(d),
            }
        } else {
            self.inner.seek(to)?
        };
        self.end = self.end.max(self.pos);
        Ok(self.pos)
    }
}

/// The I/O error inside a zip error (so "No space left on device" reads as such), or the
/// zip error itself.
fn io_error(e: zip::result::ZipError) -> io::Error {
    match e {
        zip::result::ZipError::Io(e) => e,
        e => io::Error::other(e),
    }
}

/// Starts the zip entry `<name>.npy` of `header` and `body_len` more bytes, and writes
/// `header`.
fn start_entry<W: Write + Seek>(
    zip: &mut zip::ZipWriter<W>,
    name: &str,
    header: &[u8],
    body_len: u64,
) -> io::Result<()> {
    let opts =
        zip::write::SimpleFileOptions::default().compression_method(zip::CompressionMethod::Stored);
    // Zip64 only for an array of 4 GiB or more (numpy reads both); smaller ones keep the
    // plain header, so their bytes do not change.
    let len = (header.len() as u64).saturating_add(body_len);
    let large = u32::try_from(len).is_err();
    zip.start_file(format!("{name}.npy"), opts.large_file(large))
        .map_err(io_error)?;
    zip.write_all(header)
}

/// One `.npy` file: header and C-order data.
#[cfg(test)]
fn npy(shape: &[usize], data: &Data) -> Vec<u8> {
    let (descr, body) = npy_body(data);
    let mut out = npy_header(shape, &descr);
    out.extend_from_slice(&body);
    out
}

/// An array's numpy type (`descr`) and C-order bytes.
fn npy_body(data: &Data) -> (String, Vec<u8>) {
    match data {
        Data::F32(v) => (
            "<f4".to_string(),
            v.iter().flat_map(|x| x.to_le_bytes()).collect(),
        ),
        Data::I32(v) => (
            "<i4".to_string(),
            v.iter().flat_map(|x| x.to_le_bytes()).collect(),
        ),
        Data::Str(v) => {
            let width = v
                .iter()
                .map(|s| s.chars().count())
                .max()
                .unwrap_or(0)
                .max(1);
            let mut body = Vec::with_capacity(v.len() * width * 4);
            for s in v {
                let n = s.chars().count();
                for c in s.chars().chain(std::iter::repeat_n('\0', width - n)) {
                    body.extend_from_slice(&(c as u32).to_le_bytes());
                }
            }
            (format!("<U{width}"), body)
        }
    }
}

/// The `.npy` header of an array of `shape` and numpy type `descr`: magic, version, length
/// and the padded dict; the data follows it.
fn npy_header(shape: &[usize], descr: &str) -> Vec<u8> {
    let shape_text = match shape {
        [n] => format!("({n},)"),
        dims => format!(
            "({})",
            dims.iter()
                .map(|d| d.to_string())
                .collect::<Vec<_>>()
                .join(", ")
        ),
    };
    let mut header =
        format!("{{'descr': '{descr}', 'fortran_order': False, 'shape': {shape_text}, }}");
    // magic(6) + version(2) + len(2) + header + '\n' must be a multiple of 64.
    let unpadded = 10 + header.len() + 1;
    header.push_str(&" ".repeat((64 - unpadded % 64) % 64));
    header.push('\n');
    let mut out = Vec::with_capacity(10 + header.len());
    out.extend_from_slice(b"\x93NUMPY\x01\x00");
    out.extend_from_slice(&(header.len() as u16).to_le_bytes());
    out.extend_from_slice(header.as_bytes());
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn header_is_aligned_and_literal() {
        let bytes = npy(&[2, 3], &Data::F32(vec![0.0; 6]));
        assert_eq!(&bytes[..8], b"\x93NUMPY\x01\x00");
        let hlen = u16::from_le_bytes([bytes[8], bytes[9]]) as usize;
        assert_eq!((10 + hlen) % 64, 0);
        let header = std::str::from_utf8(&bytes[10..10 + hlen]).unwrap();
        assert!(header.starts_with("{'descr': '<f4', 'fortran_order': False, 'shape': (2, 3), }"));
        assert!(header.ends_with('\n'));
        assert_eq!(bytes.len(), 10 + hlen + 24);
        let s = npy(&[2], &Data::Str(vec!["ab".into(), "c".into()]));
        let hlen = u16::from_le_bytes([s[8], s[9]]) as usize;
        assert!(std::str::from_utf8(&s[10..10 + hlen])
            .unwrap()
            .contains("'<U2'"));
        assert_eq!(s.len(), 10 + hlen + 16);
    }

    /// A file that holds at most `room` bytes, like a full disk.
    struct Full {
        inner: Cursor<Vec<u8>>,
        room: u64,
    }

    impl Write for Full {
        fn write(&mut self, buf: &[u8]) -> io::Result<usize> {
            if self.inner.position() + buf.len() as u64 > self.room {
                return Err(io::Error::new(io::ErrorKind::StorageFull, "full"));
            }
            self.inner.write(buf)
        }

        fn flush(&mut self) -> io::Result<()> {
            Ok(())
        }
    }

    impl Seek for Full {
        fn seek(&mut self, pos: io::SeekFrom) -> io::Result<u64> {
            self.inner.seek(pos)
        }
    }

    #[test]
    fn streamed_bytes_are_the_in_memory_bytes_and_a_full_sink_fails() {
        let dir = tempfile::tempdir().expect("tempdir");
        let build = |spill_dir: Option<&std::path::Path>| {
            let mut npz = NpzWriter::default();
            npz.add("names", &[2], Data::Str(vec!["a".into(), "bc".into()]));
            let mut spill = Spill::new(spill_dir);
            spill.extend_f32(&[1.0, 2.0, 3.0, 4.0]).expect("append");
            npz.add_spill("values", &[2, 2], spill);
            npz.add("ids", &[1], Data::I32(vec![7]));
            npz
        };
        let bytes = build(None).finish().expect("in memory");
        let file = build(Some(dir.path()))
            .write_to(tempfile::tempfile_in(dir.path()).expect("file"))
            .expect("streamed");
        let mut streamed = Vec::new();
        let mut file = file;
        file.seek(io::SeekFrom::Start(0)).expect("seek");
        io::Read::read_to_end(&mut file, &mut streamed).expect("read");
        assert_eq!(streamed, bytes);
        for room in [0, 10, 100, bytes.len() as u64 - 1] {
            let full = Full {
                inner: Cursor::new(Vec::new()),
                room,
            };
            let err = build(None).write_to(full).map(|_| ()).unwrap_err();
            assert_eq!(err.kind(), io::ErrorKind::StorageFull, "room {room}: {err}");
        }
    }
}
