//! What `verify` compares and how strictly: [`VerifyOptions`], with the clips ([`Clips`])
//! and times ([`Times`]) chosen.

use std::path::PathBuf;

use crate::load::Input;

/// The default tolerance: deviations up to this fraction of the reference's bounding-box
/// diagonal pass (1e-4: 0.2 mm on a 2 m character, below what a viewer shows; a file
/// written and read back by rigport in any format keeps every corpus asset within 1e-5,
/// which `--tol 1e-5` asks for).
///
/// ```
/// assert_eq!(rigport_pipeline::verify::DEFAULT_TOLERANCE, 1e-4);
/// ```
pub const DEFAULT_TOLERANCE: f64 = 1e-4;

/// Which clips are compared.
///
/// ```
/// use rigport_pipeline::verify::Clips;
/// assert_eq!(Clips::default(), Clips::First);
/// ```
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub enum Clips {
    /// The reference's first clip (the rest pose without clips).
    #[default]
    First,
    /// The reference's clip of this name.
    Named(String),
    /// Every paired clip.
    All,
}

impl Clips {
    /// The choice a command line's `--clip NAME` and `--all-clips` make.
    ///
    /// ```
    /// use rigport_pipeline::verify::Clips;
    /// assert_eq!(Clips::from_flags(None, true), Clips::All);
    /// assert_eq!(Clips::from_flags(Some("walk"), false), Clips::Named("walk".into()));
    /// ```
    pub fn from_flags(name: Option<&str>, all: bool) -> Self {
        match (name, all) {
            (Some(name), _) => Self::Named(name.to_string()),
            (None, true) => Self::All,
            (None, false) => Self::First,
        }
    }
}

/// When the clips are compared.
///
/// ```
/// use rigport_pipeline::verify::Times;
/// assert_eq!(Times::default(), Times::KeyUnion);
/// ```
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub enum Times {
    /// At every key time of either clip.
    #[default]
    KeyUnion,
    /// Every `1 / fps` seconds from the earlier start to the later end.
    Fps(f32),
    /// At the key times both clips share (the reference's when they share none).
    AtKeys,
}

impl Times {
    /// The choice a command line's `--fps F` and `--at-keys` make.
    ///
    /// ```
    /// use rigport_pipeline::verify::Times;
    /// assert_eq!(Times::from_flags(Some(30.0), false), Times::Fps(30.0));
    /// assert_eq!(Times::from_flags(None, true), Times::AtKeys);
    /// ```
    pub fn from_flags(fps: Option<f32>, at_keys: bool) -> Self {
        match (fps, at_keys) {
            (Some(fps), _) => Self::Fps(fps),
            (None, true) => Self::AtKeys,
            (None, false) => Self::KeyUnion,
        }
    }
}

/// What `verify` compares, and how strictly.
///
/// ```
/// use rigport_pipeline::verify::{Clips, VerifyOptions};
/// use rigport_pipeline::load::Input;
/// let options = VerifyOptions::new(Input::new(vec!["walk.glb".into()]));
/// assert_eq!((options.clips, options.tolerance), (Clips::First, 1e-4));
/// ```
#[derive(Clone, Debug)]
pub struct VerifyOptions {
    /// The candidate file(s).
    pub candidate: Input,
    /// Which clips.
    pub clips: Clips,
    /// When.
    pub times: Times,
    /// Deviations up to this fraction of the reference's diagonal pass.
    pub tolerance: f64,
    /// The report as JSON (in [`crate::Report::output`]) instead of text (in
    /// [`crate::Report::summary`]).
    pub json: bool,
    /// A PNG of the worst frame: the reference coloured by deviation, with a colour scale.
    pub picture: Option<PathBuf>,
}

impl VerifyOptions {
    /// `candidate` against the first clip, at both clips' key times, within
    /// [`DEFAULT_TOLERANCE`], as text, without a picture.
    ///
    /// ```
    /// use rigport_pipeline::verify::VerifyOptions;
    /// let options = VerifyOptions::new(rigport_pipeline::load::Input::new(vec!["b.usdz".into()]));
    /// assert!(!options.json && options.picture.is_none());
    /// ```
    pub fn new(candidate: Input) -> Self {
        Self {
            candidate,
            clips: Clips::First,
            times: Times::KeyUnion,
            tolerance: DEFAULT_TOLERANCE,
            json: false,
            picture: None,
        }
    }
}
