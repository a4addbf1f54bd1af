//! Why the demo could not be built.

use rigport_deform::bake::asset::DqsBakeError;
use rigport_eval::sample::SampleError;
use rigport_ik::clip::ClipSolveError;
use rigport_import::ImportError;

/// Why the demo could not be built: each is a rigport bug for the built-in character,
/// except [`DemoError::Corpus`] and [`DemoError::Render`] of a corpus rig.
#[derive(Debug, thiserror::Error)]
pub enum DemoError {
    /// The character does not assemble as a Pinocchio rig.
    #[error("the built-in demo rig is invalid (a rigport bug)")]
    Assemble(#[source] ImportError),
    /// Keys or handles name a joint the skeleton lacks.
    #[error("no joint named {0:?}")]
    UnknownJoint(String),
    /// A keyed clip cannot be baked.
    #[error("cannot bake the keys of clip {clip:?}")]
    Keys {
        /// The clip.
        clip: String,
        /// Why.
        #[source]
        source: SampleError,
    },
    /// The IK reach cannot be solved.
    #[error("the built-in demo reach is invalid (a rigport bug)")]
    Reach(#[source] ClipSolveError),
    /// The twist clip's DQS cannot be baked.
    #[error("cannot bake the demo's twist clip (a rigport bug)")]
    Bake(#[source] DqsBakeError),
    /// The demo's skirt cannot be simulated.
    #[error("cannot simulate the demo's skirt (a rigport bug)")]
    Cloth(#[source] rigport_deform::cloth::ClothError),
    /// A picture cannot be rendered.
    #[error("cannot render {what}")]
    Render {
        /// The clip or rig.
        what: String,
        /// Why.
        #[source]
        source: rigport_render::RenderError,
    },
    /// A corpus rig cannot be opened.
    #[error(transparent)]
    Corpus(#[from] rigport_import::detect::OpenError),
    /// A corpus family's files make more or fewer than one rig.
    #[error("expected one rig, found {0}")]
    CorpusRigs(usize),
}
