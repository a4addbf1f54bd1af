//! The asset file formats rigport writes, named by the output path's extension.

use std::path::Path;

/// An asset file format rigport writes; the output path's extension says which.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum OutputFormat {
    /// `.glb`: binary glTF 2.0, one file.
    Glb,
    /// `.gltf`: glTF 2.0 JSON, with its buffer in a `.bin` beside it.
    Gltf,
    /// `.usda`: USD text.
    Usda,
    /// `.usdc`: a USD crate (binary) file.
    Usdc,
    /// `.usdz`: a USD package (a `.usdc` root layer and its textures, stored).
    Usdz,
}

/// An output path whose extension names no format rigport writes.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
pub enum OutputFormatError {
    /// `.usd` may hold text or a crate file: the encoding must be said.
    #[error("say which USD encoding: .usda (text), .usdc (binary) or .usdz (package)")]
    UsdEncodingUnsaid,
    /// Any other extension (or none).
    #[error("unknown output type; expected {}", OutputFormat::expected())]
    Unknown {
        /// The lower-case extension ("" when the path has none).
        extension: String,
    },
}

impl OutputFormat {
    /// Every format, in the order messages list them.
    pub const ALL: [OutputFormat; 5] = [Self::Glb, Self::Gltf, Self::Usda, Self::Usdc, Self::Usdz];

    /// The file extension, lower case, without the dot.
    pub fn extension(self) -> &'static str {
        match self {
            Self::Glb => "glb",
            Self::Gltf => "gltf",
            Self::Usda => "usda",
            Self::Usdc => "usdc",
            Self::Usdz => "usdz",
        }
    }

    /// The format an extension (without the dot, any case) names.
    ///
    /// # Errors
    /// [`OutputFormatError`] for `usd` (ambiguous) and any extension rigport does not write.
    pub fn from_extension(extension: &str) -> Result<Self, OutputFormatError> {
        let lower = extension.to_ascii_lowercase();
        if lower == "usd" {
            return Err(OutputFormatError::UsdEncodingUnsaid);
        }
        Self::ALL
            .into_iter()
            .find(|f| f.extension() == lower)
            .ok_or(OutputFormatError::Unknown { extension: lower })
    }

    /// The format `path`'s extension names.
    ///
    /// # Errors
    /// As [`OutputFormat::from_extension`].
    pub fn of_path(path: &Path) -> Result<Self, OutputFormatError> {
        Self::from_extension(path.extension().and_then(|e| e.to_str()).unwrap_or(""))
    }

    /// glTF 2.0 (`.glb` or `.gltf`).
    pub fn is_gltf(self) -> bool {
        matches!(self, Self::Glb | Self::Gltf)
    }

    /// USD (`.usda`, `.usdc` or `.usdz`).
    pub fn is_usd(self) -> bool {
        !self.is_gltf()
    }

    /// ".glb, .gltf, .usda, .usdc or .usdz", for messages.
    pub fn expected() -> String {
        let names: Vec<String> = Self::ALL
            .iter()
            .map(|f| format!(".{}", f.extension()))
            .collect();
        let (last, rest) = names.split_last().unwrap_or((&names[0], &[]));
        format!("{} or {last}", rest.join(", "))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn extensions_round_trip_in_any_case_and_usd_needs_an_encoding() {
        for f in OutputFormat::ALL {
            assert_eq!(OutputFormat::from_extension(f.extension()), Ok(f));
            assert_eq!(
                OutputFormat::of_path(Path::new(&format!("a/B.{}", f.extension().to_uppercase()))),
                Ok(f)
            );
        }
        assert_eq!(
            OutputFormat::from_extension("usd"),
            Err(OutputFormatError::UsdEncodingUnsaid)
        );
        assert!(matches!(
            OutputFormat::of_path(Path::new("x")),
            Err(OutputFormatError::Unknown { .. })
        ));
        assert_eq!(
            OutputFormat::expected(),
            ".glb, .gltf, .usda, .usdc or .usdz"
        );
        assert!(OutputFormat::Gltf.is_gltf() && OutputFormat::Usdz.is_usd());
    }
}

/// How a glTF writer compresses binary data beyond core glTF.
///
/// ```
/// use rigport_model::Compression;
/// assert_eq!(Compression::default(), Compression::None);
/// assert_eq!(Compression::Meshopt.extension(), Some("EXT_meshopt_compression"));
/// ```
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "clap", derive(clap::ValueEnum))]
pub enum Compression {
    /// Core glTF only: every viewer reads the file.
    #[default]
    None,
    /// `EXT_meshopt_compression` (declared required): animation data and vertex attributes
    /// through meshoptimizer's vertex codec, rotations with its quaternion filter and
    /// translations and scales with its exponential filter; three.js, Babylon.js and
    /// gltfpack decode it.
    Meshopt,
}

impl Compression {
    /// The glTF extension the compression needs, if any.
    pub fn extension(self) -> Option<&'static str> {
        match self {
            Compression::None => None,
            Compression::Meshopt => Some("EXT_meshopt_compression"),
        }
    }
}
