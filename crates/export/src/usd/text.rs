//! Where USDA text goes: in memory, or streamed into the output's temporary file once it
//! is long. `rigport-usd`'s printer ([`rigport_usd::printer::UsdaPrinter`]) writes the lines
//! into a [`Usda`], which moves them to the file as they come.

use std::fs::File;
use std::io::{self, BufWriter, Write as _};
use std::path::{Path, PathBuf};

use rigport_atomic::TempFile;
use rigport_usd::printer::TextOut;

/// Text held in memory before a spilling document moves it to its temporary file (and the
/// size of each later write): long clips become files of gigabytes that never sit in memory
/// whole, while every smaller file is built in memory as before.
pub(crate) const SPILL_BYTES: usize = 64 << 20;

/// A USDA document being written: in memory, or (with [`Usda::spilling_to`]) streamed to
/// a temporary file beside the output once it outgrows [`SPILL_BYTES`].
#[derive(Debug, Default)]
pub(crate) struct Usda {
    out: String,
    spill: Option<Spill>,
}

/// Where a spilling document goes.
#[derive(Debug)]
struct Spill {
    /// The output the temporary file will be renamed to (links already followed).
    target: PathBuf,
    /// Text held before a spill ([`SPILL_BYTES`] but in tests).
    at: usize,
    /// Created at the first spill.
    file: Option<(TempFile, BufWriter<File>)>,
    /// The first I/O error; the text after it is dropped, since the export has failed.
    error: Option<io::Error>,
}

/// A finished document.
#[derive(Debug)]
pub(crate) enum Finished {
    /// All of it, in memory.
    Text(String),
    /// Written to a temporary file beside `target`, to be renamed over it.
    Staged {
        /// The temporary file (removed on drop unless persisted).
        file: TempFile,
        /// The output it replaces.
        target: PathBuf,
        /// The text's length in bytes.
        len: u64,
    },
}

impl Usda {
    /// A document that moves its text to a temporary file beside `target` (the output;
    /// links already followed, see [`rigport_atomic::check_output`]) once it holds more than
    /// `at` bytes ([`SPILL_BYTES`]).
    pub(crate) fn spilling_to(target: &Path, at: usize) -> Self {
        Self {
            spill: Some(Spill {
                target: target.to_path_buf(),
                at,
                file: None,
                error: None,
            }),
            ..Self::default()
        }
    }

    /// The document: its text, or its temporary file when it spilled.
    ///
    /// # Errors
    /// The first I/O error creating or writing the temporary file (then removed).
    pub(crate) fn finish(mut self) -> io::Result<Finished> {
        let Some(mut spill) = self.spill.take() else {
            return Ok(Finished::Text(self.out));
        };
        if let Some(e) = spill.error.take() {
            return Err(e);
        }
        match spill.file.take() {
            None => Ok(Finished::Text(self.out)),
            Some((file, mut writer)) => {
                writer.write_all(self.out.as_bytes())?;
                writer.flush()?;
                let len = writer.get_ref().metadata()?.len();
                drop(writer);
                Ok(Finished::Staged {
                    file,
                    target: spill.target,
                    len,
                })
            }
        }
    }

    /// The text in memory when it ends a line, spilling it if it grew past [`SPILL_BYTES`].
    fn maybe_spill(&mut self) {
        let Some(spill) = self.spill.as_mut() else {
            return;
        };
        if self.out.len() < spill.at {
            return;
        }
        if spill.error.is_none() {
            let result = match spill.file.as_mut() {
                Some((_, writer)) => writer.write_all(self.out.as_bytes()),
                None => TempFile::create_beside_open(&spill.target).and_then(|(tmp, file)| {
                    let mut writer = BufWriter::with_capacity(1 << 20, file);
                    writer.write_all(self.out.as_bytes())?;
                    spill.file = Some((tmp, writer));
                    Ok(())
                }),
            };
            if let Err(e) = result {
                spill.error = Some(e);
                // The temporary file goes now; the export fails at `finish`.
                spill.file = None;
            }
        }
        self.out.clear();
    }
}

impl TextOut for Usda {
    fn text(&mut self) -> &mut String {
        &mut self.out
    }

    fn line_done(&mut self) {
        self.maybe_spill();
    }
}
