//! One contact sheet per corpus family, each rig loaded the way `rigport render` loads it.

use std::path::Path;

use rigport_import::detect::{self, Inputs};
use rigport_render::{RenderOptions, View};

use crate::pictures::CELL_PX;
use crate::DemoError;

/// One rig of a shared corpus family (paths relative to the corpus folder).
#[derive(Clone, Copy, Debug)]
pub struct CorpusRig {
    /// The family folder, also the picture's name (`corpus/<family>.png`).
    pub family: &'static str,
    /// Input files, as `rigport render` takes them.
    pub files: &'static [&'static str],
    /// Whether the rig gets the small posed clip of [`crate::clips::model1_keys`] (its
    /// example file is [`crate::clips::MODEL1_KEYS_JSON`]); otherwise its own first clip, or
    /// the rest pose, is drawn.
    pub model1_keys: bool,
    /// Where the camera looks from.
    pub view: View,
}

/// The corpus rigs the demo renders, one per family.
pub const CORPUS_RIGS: [CorpusRig; 6] = [
    CorpusRig {
        family: "1_pinocchio",
        files: &[
            "1_pinocchio/berkeley_cs184__severus-snape_mobius-ants/human_model1/Model1.obj",
            "1_pinocchio/berkeley_cs184__severus-snape_mobius-ants/human_model1/skeleton.out",
            "1_pinocchio/berkeley_cs184__severus-snape_mobius-ants/human_model1/attachment.out",
        ],
        model1_keys: true,
        view: View::Front,
    },
    CorpusRig {
        family: "2_csci520_ik_skinning",
        files: &["2_csci520_ik_skinning/tydia/armadillo/skin.config"],
        model1_keys: false,
        view: View::ThreeQuarter,
    },
    CorpusRig {
        family: "3_acclaim_asf_amc",
        files: &[
            "3_acclaim_asf_amc/usc_csci520_mocapPlayer__shreyabhaumik/07-walk.asf",
            "3_acclaim_asf_amc/usc_csci520_mocapPlayer__shreyabhaumik/07_05-walk.amc",
        ],
        model1_keys: false,
        view: View::Front,
    },
    CorpusRig {
        family: "4_bvh",
        files: &["4_bvh/bandai_namco_ds1/dataset-1_walk_normal_002.bvh"],
        model1_keys: false,
        view: View::Side,
    },
    CorpusRig {
        family: "5_gltf",
        files: &["5_gltf/khronos_samples__nobuyuki83_delfem2/CesiumMan.glb"],
        model1_keys: false,
        view: View::Front,
    },
    CorpusRig {
        family: "6_usd",
        files: &["6_usd/openusd_usdskel__PixarAnimationStudios/testUsdSkelBakeSkinning/dqs.usda"],
        model1_keys: false,
        view: View::Front,
    },
];

/// A corpus rig's contact sheet.
#[derive(Clone, Debug, PartialEq)]
pub struct CorpusPicture {
    /// The PNG bytes.
    pub png: Vec<u8>,
    /// The rig's label (its main file).
    pub label: String,
    /// The clip drawn, `None` for the rest pose.
    pub clip: Option<String>,
    /// Frames drawn and frames in the clip.
    pub frames_drawn: usize,
    /// Frames in the clip.
    pub frames: usize,
}

/// Loads `rig` from the `corpus` folder as `rigport render` does (a skeleton-only rig gets
/// a bone mesh) and draws its contact sheet.
///
/// # Errors
/// The rig does not open, is not one rig, or does not render.
pub fn picture(corpus: &Path, rig: &CorpusRig) -> Result<CorpusPicture, DemoError> {
    let inputs = Inputs::new(rig.files.iter().map(|f| corpus.join(f)).collect());
    let mut opened = detect::open(&inputs)?;
    if opened.len() != 1 {
        return Err(DemoError::CorpusRigs(opened.len()));
    }
    let (source, mut imported) = opened.remove(0);
    rigport_import::bone_mesh::add_bone_mesh(&mut imported.asset);
    let label = source.label();
    let asset = &mut imported.asset;
    if rig.model1_keys {
        let keys = crate::clips::model1_keys(&asset.skeleton)?;
        let clip = rigport_anim::keyed::clip(&asset.skeleton, &keys, "demo").map_err(|source| {
            DemoError::Keys {
                clip: "arms".into(),
                source,
            }
        })?;
        asset.clips.insert(0, clip);
    }
    let failed = |source| DemoError::Render {
        what: label.clone(),
        source,
    };
    let clip = rigport_render::find_clip(asset, None).map_err(failed)?;
    let frames = rigport_render::frame_list(asset, clip, None, None).map_err(failed)?;
    let options = RenderOptions {
        width: CELL_PX,
        height: CELL_PX,
        view: rig.view,
        ..RenderOptions::default()
    };
    let png =
        rigport_render::render_sheet_png(asset, clip, &frames, None, &options).map_err(failed)?;
    Ok(CorpusPicture {
        png,
        clip: clip.map(|c| c.name.clone()),
        frames_drawn: frames.len().min(rigport_render::SHEET_FRAMES),
        frames: frames.len(),
        label,
    })
}
