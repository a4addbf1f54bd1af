//! An append-only byte buffer that moves to an unnamed temporary file once it outgrows a
//! memory limit, so that an array of any length costs at most the limit in memory.

use std::fs::File;
use std::io::{self, Read, Seek, SeekFrom, Write};
use std::path::{Path, PathBuf};

/// Bytes held in memory per spill before they go to the file: large enough that the file
/// sees few, large writes; small enough that the four per-frame arrays of a dump stay
/// well under a few hundred MB whatever the frame count.
pub const SPILL_LIMIT: usize = 64 << 20;

/// Bytes read from the file per copy step.
const COPY_CHUNK: usize = 1 << 20;

/// Appended bytes: the first [`SPILL_LIMIT`] in memory; beyond that, with a folder to
/// spill into, the memory buffer is flushed to an unnamed temporary file in that folder
/// (`tempfile::tempfile_in`: removed by the OS when closed, even if the process is killed)
/// and reused. Without a folder everything stays in memory.
#[derive(Debug)]
pub(crate) struct Spill {
    /// Where the file goes, `None`: never spill.
    dir: Option<PathBuf>,
    /// The bytes not yet in `file`.
    memory: Vec<u8>,
    /// The spilled bytes, written from its start.
    file: Option<File>,
    /// Total bytes appended.
    len: u64,
    /// Bytes held in memory before they spill ([`SPILL_LIMIT`]; smaller in tests).
    limit: usize,
}

impl Spill {
    /// An empty spill; `dir` is the folder for the temporary file (the output's own
    /// folder, so the bytes land on the disk that is to hold the output, not on a tmpfs).
    pub(crate) fn new(dir: Option<&Path>) -> Self {
        Self {
            dir: dir.map(Path::to_path_buf),
            memory: Vec::new(),
            file: None,
            len: 0,
            limit: SPILL_LIMIT,
        }
    }

    /// Total bytes appended.
    pub(crate) fn len(&self) -> u64 {
        self.len
    }

    /// Appends `values` as little-endian f32.
    ///
    /// # Errors
    /// Creating or writing the temporary file.
    pub(crate) fn extend_f32(&mut self, values: &[f32]) -> io::Result<()> {
        let bytes = values.len() * 4;
        if self.dir.is_some() && self.memory.len() + bytes > self.limit {
            self.flush_memory()?;
        }
        self.memory.reserve(bytes);
        for v in values {
            self.memory.extend_from_slice(&v.to_le_bytes());
        }
        self.len += bytes as u64;
        // A single append larger than the limit goes straight on.
        if self.dir.is_some() && self.memory.len() > self.limit {
            self.flush_memory()?;
        }
        Ok(())
    }

    /// Writes the memory buffer to the file (created on first use) and empties it.
    fn flush_memory(&mut self) -> io::Result<()> {
        if self.memory.is_empty() {
            return Ok(());
        }
        if self.file.is_none() {
            let Some(dir) = &self.dir else {
                return Ok(());
            };
            self.file = Some(tempfile::tempfile_in(dir)?);
        }
        if let Some(file) = &mut self.file {
            file.write_all(&self.memory)?;
            self.memory.clear();
        }
        Ok(())
    }

    /// Writes every appended byte, in order, to `sink`.
    ///
    /// # Errors
    /// Reading the temporary file (or it holding fewer bytes than were appended); writing
    /// to `sink`.
    pub(crate) fn copy_to(mut self, sink: &mut impl Write) -> io::Result<()> {
        let Some(mut file) = self.file.take() else {
            return sink.write_all(&self.memory);
        };
        // The tail still in memory follows the file's bytes.
        file.seek(SeekFrom::Start(0))?;
        let on_file = self.len - self.memory.len() as u64;
        let mut buf = vec![0; COPY_CHUNK];
        let mut left = on_file;
        while left > 0 {
            let n = (left.min(COPY_CHUNK as u64)) as usize;
            file.read_exact(&mut buf[..n])?;
            sink.write_all(&buf[..n])?;
            left -= n as u64;
        }
        sink.write_all(&self.memory)
    }

    /// Every appended value, in order.
    ///
    /// # Errors
    /// As [`Spill::copy_to`].
    pub(crate) fn into_f32(self) -> io::Result<Vec<f32>> {
        let mut bytes = Vec::with_capacity(usize::try_from(self.len).unwrap_or(0));
        self.copy_to(&mut bytes)?;
        Ok(bytes
            .chunks_exact(4)
            .map(|b| f32::from_le_bytes([b[0], b[1], b[2], b[3]]))
            .collect())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A spill with a small limit, so the tests stay small.
    const LIMIT: usize = 4096;

    fn small(dir: Option<&Path>) -> Spill {
        Spill {
            limit: LIMIT,
            ..Spill::new(dir)
        }
    }

    fn bytes_of(values: &[f32]) -> Vec<u8> {
        values.iter().flat_map(|v| v.to_le_bytes()).collect()
    }

    #[test]
    fn in_memory_and_spilled_copies_are_the_same_bytes() {
        let dir = tempfile::tempdir().expect("tempdir");
        // Appends of a quarter, then three quarters of the limit plus a bit, then more than
        // the limit at once: every path through `extend_f32`.
        let quarter = LIMIT / 16;
        let chunks: Vec<Vec<f32>> = [quarter, 3 * quarter + 3, 4 * quarter + 5, 7]
            .iter()
            .enumerate()
            .map(|(c, &n)| (0..n).map(|i| (i * 7 + c) as f32).collect())
            .collect();
        let mut expected = Vec::new();
        let mut memory = small(None);
        let mut spilled = small(Some(dir.path()));
        for chunk in &chunks {
            expected.extend(bytes_of(chunk));
            memory.extend_f32(chunk).expect("append");
            spilled.extend_f32(chunk).expect("append");
        }
        assert!(memory.file.is_none());
        assert!(spilled.file.is_some(), "spilled past the limit");
        assert!(spilled.memory.len() <= LIMIT);
        assert_eq!(spilled.len(), expected.len() as u64);
        for spill in [memory, spilled] {
            let mut out = Vec::new();
            spill.copy_to(&mut out).expect("copy");
            assert_eq!(out, expected);
        }
        // The file has no name: the folder stays empty.
        assert_eq!(std::fs::read_dir(dir.path()).expect("dir").count(), 0);
    }

    #[test]
    fn a_missing_folder_fails_when_it_spills() {
        let dir = tempfile::tempdir().expect("tempdir");
        let mut spill = small(Some(&dir.path().join("gone")));
        spill.extend_f32(&[1.0; 16]).expect("in memory");
        let big = vec![0.0; LIMIT / 4 + 1];
        assert!(spill.extend_f32(&big).is_err());
    }
}
