//! One function per command, with the CLI's options as keyword arguments: each builds the
//! command's options (the CLI's parsers for values written as text: `"0.5..1.5"`,
//! `"512x512"`) and calls its pipeline function with the GIL released.

use std::path::PathBuf;
use std::str::FromStr as _;

use pyo3::prelude::*;
use pyo3::types::PyDict;
use rigport_anim::retime::{Retime, WarpCurve};
use rigport_anim::root_motion::RootMotionOptions;
use rigport_deform::cloth::PinSelection;
use rigport_ik::clip::ClipSolveOptions;
use rigport_ik::footlock::{FootlockOptions, PinAt};
use rigport_ik::retarget::RetargetOptions;
use rigport_ik::{IkMethod, Lambda};
use rigport_pipeline::PipelineError;
use rigport_pipeline::load::Input;
use rigport_pipeline::render as render_pipeline;
use rigport_pipeline::retime as retime_pipeline;
use rigport_pipeline::write::Output;
use rigport_render::{Projection, RenderOptions, View};

use crate::asset::Asset;
use crate::errors::{PyProgress, usage};
use crate::options::{self, OutputOptions};
use crate::report::Report;

/// Adds the command functions to the module.
pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(convert, m)?)?;
    m.add_function(wrap_pyfunction!(inspect, m)?)?;
    m.add_function(wrap_pyfunction!(animate, m)?)?;
    m.add_function(wrap_pyfunction!(sequence, m)?)?;
    m.add_function(wrap_pyfunction!(retime, m)?)?;
    m.add_function(wrap_pyfunction!(bake, m)?)?;
    m.add_function(wrap_pyfunction!(retarget, m)?)?;
    m.add_function(wrap_pyfunction!(combine, m)?)?;
    m.add_function(wrap_pyfunction!(ik, m)?)?;
    m.add_function(wrap_pyfunction!(footlock, m)?)?;
    m.add_function(wrap_pyfunction!(cloth, m)?)?;
    m.add_function(wrap_pyfunction!(render, m)?)?;
    m.add_function(wrap_pyfunction!(skin, m)?)?;
    m.add_function(wrap_pyfunction!(verify, m)?)?;
    Ok(())
}

/// A command's input: an `Asset` (its files, read again with its options), a path, or a
/// list of paths (read as the CLI reads its inputs, with its default options).
fn input_of(input: &Bound<'_, PyAny>) -> PyResult<Input> {
    if let Ok(asset) = input.cast::<Asset>() {
        return Ok(asset.get().input.clone());
    }
    let paths: Vec<PathBuf> = match input.extract::<PathBuf>() {
        Ok(path) => vec![path],
        Err(_) => input.extract()?,
    };
    options::input(
        paths,
        &options::InputOptions {
            bone_mesh: true,
            ..Default::default()
        },
    )
}

/// The writing options and root motion among a command's `**options`: the keys of
/// `Asset.write` (max_influences, influences_fit, reduce_tolerance, reduce, reduce_cubic, compress,
/// skinning, up_axis,
/// meters_per_unit; root_motion, root_yaw, root_window with `root`).
///
/// # Errors
/// An unknown key, or a value of the wrong type or range.
fn write_options(
    path: PathBuf,
    kwargs: Option<&Bound<'_, PyDict>>,
    root: bool,
) -> PyResult<(Output, RootMotionOptions)> {
    let mut o = OutputOptions::default();
    let (mut mode, mut yaw, mut window) = ("keep".to_string(), false, None);
    for (key, value) in kwargs.into_iter().flatten() {
        let key: String = key.extract()?;
        match key.as_str() {
            "max_influences" => o.max_influences = value.extract()?,
            "influences_fit" => o.influences_fit = value.extract()?,
            "reduce_tolerance" => o.reduce_tolerance = value.extract()?,
            "reduce" => o.reduce = value.extract()?,
            "reduce_cubic" => o.reduce_cubic = value.extract()?,
            "compress" => o.compress = value.extract()?,
            "skinning" => o.skinning = value.extract()?,
            "up_axis" => o.up_axis = value.extract()?,
            "meters_per_unit" => o.meters_per_unit = value.extract()?,
            "root_motion" if root => mode = value.extract()?,
            "root_yaw" if root => yaw = value.extract()?,
            "root_window" if root => window = value.extract()?,
            other => return Err(usage(format!("unexpected keyword argument {other:?}"))),
        }
    }
    let output = options::output(path, &o)?;
    Ok((output, options::root_motion(&mode, yaw, window)?))
}

/// Runs `command` with the GIL released; its report, or its error as Python's.
fn run(
    py: Python<'_>,
    command: impl FnOnce(&PyProgress) -> Result<rigport_pipeline::Report, PipelineError> + Send,
) -> PyResult<Report> {
    let progress = PyProgress::default();
    let result = py.detach(|| command(&progress));
    let report = result.map_err(|e| progress.error(py, &e))?;
    Ok(Report::new(report, &progress))
}

/// A usage error for text the CLI's parser refuses.
fn parsed<T>(name: &str, text: &str, result: Result<T, String>) -> PyResult<T> {
    result.map_err(|e| usage(format!("{name}={text:?}: {e}")))
}

/// `rigport convert`: reads `input` and writes it to `output` (by extension). Keyword
/// options: those of `Asset.write`.
#[pyfunction]
#[pyo3(signature = (input, output, *, json=false, **options))]
fn convert(
    py: Python<'_>,
    input: &Bound<'_, PyAny>,
    output: PathBuf,
    json: bool,
    options: Option<&Bound<'_, PyDict>>,
) -> PyResult<Report> {
    let input = input_of(input)?;
    let (output, root_motion) = write_options(output, options, true)?;
    let options = rigport_pipeline::convert::ConvertOptions {
        output,
        root_motion,
        json,
    };
    run(py, |p| rigport_pipeline::convert(&input, &options, p))
}

/// `rigport inspect`: the listing of `input` (`Report.output`), as JSON with `json`.
#[pyfunction]
#[pyo3(signature = (input, *, json=false))]
fn inspect(py: Python<'_>, input: &Bound<'_, PyAny>, json: bool) -> PyResult<Report> {
    let input = input_of(input)?;
    let options = rigport_pipeline::inspect::InspectOptions { json };
    run(py, |p| rigport_pipeline::inspect(&input, &options, p))
}

/// `rigport animate`: a clip keyed by `keys` (a KEYS.json) on `input`'s rig, written to
/// `output`. Keyword options: those of `Asset.write` but root motion.
#[pyfunction]
#[pyo3(signature = (input, keys, output, **options))]
fn animate(
    py: Python<'_>,
    input: &Bound<'_, PyAny>,
    keys: PathBuf,
    output: PathBuf,
    options: Option<&Bound<'_, PyDict>>,
) -> PyResult<Report> {
    let input = input_of(input)?;
    let (output, _) = write_options(output, options, false)?;
    let options = rigport_pipeline::animate::AnimateOptions { keys, output };
    run(py, |p| rigport_pipeline::animate(&input, &options, p))
}

/// `rigport sequence`: the clips of `input` played one after another (`crossfade`
/// frames blended, looping with `loop`), resampled at `fps`.
#[pyfunction]
#[pyo3(signature = (input, output, *, crossfade=0, r#loop=false, fps=None, **options))]
fn sequence(
    py: Python<'_>,
    input: &Bound<'_, PyAny>,
    output: PathBuf,
    crossfade: usize,
    r#loop: bool,
    fps: Option<f32>,
    options: Option<&Bound<'_, PyDict>>,
) -> PyResult<Report> {
    let input = input_of(input)?;
    let (output, _) = write_options(output, options, false)?;
    let fps = fps.map(|f| options::positive("fps", f)).transpose()?;
    let options = rigport_pipeline::sequence::SequenceOptions {
        crossfade,
        fps,
        looping: r#loop,
        output,
    };
    run(py, |p| rigport_pipeline::sequence(&input, &options, p))
}

/// `rigport retime`: one change of a clip's timing: `frames` (a count), `fps`, `speed`,
/// `warp` (the CLI's KEYS text), `reverse`, or `trim` (`"START..END"` seconds).
#[pyfunction]
#[pyo3(signature = (
    input, output, *, frames=None, fps=None, speed=None, warp=None, reverse=false, trim=None,
    clip=None, **options
))]
#[allow(clippy::too_many_arguments)] // one keyword argument per CLI option
fn retime(
    py: Python<'_>,
    input: &Bound<'_, PyAny>,
    output: PathBuf,
    frames: Option<usize>,
    fps: Option<f32>,
    speed: Option<f32>,
    warp: Option<String>,
    reverse: bool,
    trim: Option<String>,
    clip: Option<String>,
    options: Option<&Bound<'_, PyDict>>,
) -> PyResult<Report> {
    let input = input_of(input)?;
    let (output, root_motion) = write_options(output, options, true)?;
    let given = [
        frames.is_some(),
        fps.is_some(),
        speed.is_some(),
        warp.is_some(),
        reverse,
        trim.is_some(),
    ];
    if given.iter().filter(|g| **g).count() != 1 {
        return Err(usage(
            "give exactly one of frames, fps, speed, warp, reverse and trim",
        ));
    }
    let change = if let Some(n) = frames {
        if n < 2 {
            return Err(usage(format!("frames={n}: expected 2 or more")));
        }
        retime_pipeline::Change::Retime(Retime::Frames(n))
    } else if let Some(f) = fps {
        retime_pipeline::Change::Retime(Retime::Fps(options::positive("fps", f)?))
    } else if let Some(s) = speed {
        retime_pipeline::Change::Retime(Retime::Speed(options::positive("speed", s)?))
    } else if let Some(w) = &warp {
        let curve = WarpCurve::parse(w).map_err(|e| usage(format!("warp={w:?}: {e}")))?;
        retime_pipeline::Change::Retime(Retime::Warp(curve))
    } else if reverse {
        retime_pipeline::Change::Retime(Retime::Reverse)
    } else {
        let text = trim.unwrap_or_default();
        parsed("trim", &text, retime_pipeline::parse_trim(&text))?
    };
    let options = retime_pipeline::RetimeOptions {
        clip,
        change,
        output,
        root_motion,
    };
    run(py, |p| rigport_pipeline::retime(&input, &options, p))
}

/// `rigport bake`: the skinning (`"dqs"` by default as the CLI) baked into a glTF
/// (`output`), with `correctives` blend shapes fitted where LBS and the method differ
/// by more than `threshold`.
#[pyfunction]
#[pyo3(signature = (
    input, output, *, skinning=None, clip=None, fps=None, threshold=None, correctives=None,
    max_influences=4
))]
#[allow(clippy::too_many_arguments)] // one keyword argument per CLI option
fn bake(
    py: Python<'_>,
    input: &Bound<'_, PyAny>,
    output: PathBuf,
    skinning: Option<String>,
    clip: Option<String>,
    fps: Option<f32>,
    threshold: Option<f32>,
    correctives: Option<u32>,
    max_influences: u8,
) -> PyResult<Report> {
    let input = input_of(input)?;
    if !(1..=8).contains(&max_influences) {
        return Err(usage(format!(
            "max_influences={max_influences}: expected 1 to 8"
        )));
    }
    let options = rigport_pipeline::bake::BakeOptions {
        skinning: options::skinning(skinning.as_deref())?,
        clip,
        fps: fps.map(|f| options::positive("fps", f)).transpose()?,
        threshold,
        correctives,
        max_influences,
        output,
    };
    run(py, |p| rigport_pipeline::bake(&input, &options, p))
}

/// `rigport retarget`: `input`'s motion onto the rig `onto` (a path or list of paths),
/// with a joint `map` (a MAP.json) or the names matched; the report as JSON with `json`.
#[pyfunction]
#[pyo3(signature = (
    input, onto, output, *, map=None, clip=None, plant_feet=false, match_hands=false,
    allow_partial=false, json=false, **options
))]
#[allow(clippy::too_many_arguments)] // one keyword argument per CLI option
fn retarget(
    py: Python<'_>,
    input: &Bound<'_, PyAny>,
    onto: &Bound<'_, PyAny>,
    output: PathBuf,
    map: Option<PathBuf>,
    clip: Option<String>,
    plant_feet: bool,
    match_hands: bool,
    allow_partial: bool,
    json: bool,
    options: Option<&Bound<'_, PyDict>>,
) -> PyResult<Report> {
    let input = input_of(input)?;
    let onto_input = input_of(onto)?;
    let mut onto = input.clone();
    onto.files = onto_input.files;
    let (output, root_motion) = write_options(output, options, true)?;
    let request = rigport_pipeline::retarget::RetargetRequest {
        onto,
        clip,
        map,
        options: RetargetOptions {
            plant_feet,
            match_hands,
            allow_partial,
            ..RetargetOptions::default()
        },
        json,
        output,
        root_motion,
    };
    run(py, |p| rigport_pipeline::retarget(&input, &request, p))
}

/// `rigport combine`: a rig and motions (`inputs`: the rig first, then the motion files)
/// into one asset with a clip per motion; `names` maps a motion file to its clip's name.
#[pyfunction]
#[pyo3(signature = (
    inputs, output, *, names=Vec::new(), map=None, plant_feet=false, fps=None, json=false,
    **options
))]
#[allow(clippy::too_many_arguments)] // one keyword argument per CLI option
fn combine(
    py: Python<'_>,
    inputs: &Bound<'_, PyAny>,
    output: PathBuf,
    names: Vec<(String, String)>,
    map: Option<PathBuf>,
    plant_feet: bool,
    fps: Option<f32>,
    json: bool,
    options: Option<&Bound<'_, PyDict>>,
) -> PyResult<Report> {
    let (rig, motions) = rigport_pipeline::combine::split_inputs(input_of(inputs)?);
    let (output, root_motion) = write_options(output, options, true)?;
    let request = rigport_pipeline::combine::CombineRequest {
        motions,
        names,
        map,
        options: RetargetOptions {
            plant_feet,
            ..RetargetOptions::default()
        },
        fps: fps.map(|f| options::positive("fps", f)).transpose()?,
        json,
        output,
        root_motion,
    };
    run(py, |p| rigport_pipeline::combine(&rig, &request, p))
}

/// `rigport ik`: the clip solved so the IK handles (`handles`, a HANDLES.json) reach
/// their targets, with `solver` "dls" (its damping `lambda_`), "pinv", "transpose",
/// "ccd" or "fabrik".
#[pyfunction]
#[pyo3(signature = (
    input, handles, output, *, solver="dls", fps=None, tolerance=None, max_iterations=100,
    lambda_=None, substep=None, free_root=false, json=false, **options
))]
#[allow(clippy::too_many_arguments)] // one keyword argument per CLI option
fn ik(
    py: Python<'_>,
    input: &Bound<'_, PyAny>,
    handles: PathBuf,
    output: PathBuf,
    solver: &str,
    fps: Option<f32>,
    tolerance: Option<f32>,
    max_iterations: u32,
    lambda_: Option<f32>,
    substep: Option<f32>,
    free_root: bool,
    json: bool,
    options: Option<&Bound<'_, PyDict>>,
) -> PyResult<Report> {
    let input = input_of(input)?;
    let (output, _) = write_options(output, options, false)?;
    let Some(method) = IkMethod::from_name(solver) else {
        return Err(usage(format!(
            "solver={solver:?}: expected one of dls, pinv, transpose, ccd, fabrik"
        )));
    };
    let method = match (method, lambda_) {
        (IkMethod::Dls { .. }, Some(l)) if l.is_finite() && l >= 0.0 => IkMethod::Dls {
            lambda: Lambda::Fixed(l),
        },
        (IkMethod::Dls { .. }, Some(l)) => {
            return Err(usage(format!("lambda_={l}: expected a number >= 0")));
        }
        (_, Some(_)) => return Err(usage("lambda_ applies to solver \"dls\" only")),
        (m, None) => m,
    };
    let options = rigport_pipeline::ik::IkOptions {
        handles,
        solve: ClipSolveOptions {
            method,
            fps: fps.map(|f| options::positive("fps", f)).transpose()?,
            tolerance: tolerance
                .map(|t| options::positive("tolerance", t))
                .transpose()?,
            max_iterations,
            substep,
            free_root,
        },
        json,
        output,
    };
    run(py, |p| rigport_pipeline::ik(&input, &options, p))
}

/// `rigport footlock`: feet planted while in contact (`feet`: "ANKLE[,TOE]" each, or
/// found by name), the legs solved to keep them there.
#[pyfunction]
#[pyo3(signature = (
    input, output, *, clip=None, feet=Vec::new(), height=None, speed=None, blend=None,
    pin_first=false, max_stretch=None, soft=None, max_knee_speed=None, json=false, **options
))]
#[allow(clippy::too_many_arguments)] // one keyword argument per CLI option
fn footlock(
    py: Python<'_>,
    input: &Bound<'_, PyAny>,
    output: PathBuf,
    clip: Option<String>,
    feet: Vec<String>,
    height: Option<f32>,
    speed: Option<f32>,
    blend: Option<f32>,
    pin_first: bool,
    max_stretch: Option<f32>,
    soft: Option<f32>,
    max_knee_speed: Option<f32>,
    json: bool,
    options: Option<&Bound<'_, PyDict>>,
) -> PyResult<Report> {
    let input = input_of(input)?;
    let (output, _) = write_options(output, options, false)?;
    let defaults = FootlockOptions::default();
    let request = rigport_pipeline::footlock::FootlockRequest {
        clip,
        feet,
        options: FootlockOptions {
            height: height.unwrap_or(defaults.height),
            speed: speed.unwrap_or(defaults.speed),
            blend: blend.unwrap_or(defaults.blend),
            max_stretch: max_stretch.unwrap_or(defaults.max_stretch),
            soft: soft.unwrap_or(defaults.soft),
            max_knee_speed_deg: max_knee_speed.unwrap_or(defaults.max_knee_speed_deg),
            pin_at: if pin_first { PinAt::First } else { PinAt::Mean },
            ..defaults
        },
        json,
        output,
    };
    run(py, |p| rigport_pipeline::footlock(&input, &request, p))
}

/// `rigport cloth`: a garment mesh of the rig (`garment`, by name) simulated over a clip
/// and baked into `output`; pinned by vertex list, or below / above a height.
#[pyfunction]
#[pyo3(signature = (
    input, garment, output, *, clip=None, pin_vertices=Vec::new(), pin_below=None,
    pin_above=None, fps=None, seconds=None, substeps=None, thickness=None, preroll=None,
    collide_all=false, allow_unstable=false, json=false, targets=None
))]
#[allow(clippy::too_many_arguments)] // one keyword argument per CLI option
fn cloth(
    py: Python<'_>,
    input: &Bound<'_, PyAny>,
    garment: String,
    output: PathBuf,
    clip: Option<String>,
    pin_vertices: Vec<u32>,
    pin_below: Option<f32>,
    pin_above: Option<f32>,
    fps: Option<f32>,
    seconds: Option<f32>,
    substeps: Option<u32>,
    thickness: Option<f32>,
    preroll: Option<f32>,
    collide_all: bool,
    allow_unstable: bool,
    json: bool,
    targets: Option<u32>,
) -> PyResult<Report> {
    let input = input_of(input)?;
    let mut pins = Vec::new();
    if !pin_vertices.is_empty() {
        pins.push(PinSelection::Vertices(pin_vertices));
    }
    pins.extend(pin_below.map(PinSelection::Below));
    pins.extend(pin_above.map(PinSelection::Above));
    if targets == Some(0) {
        return Err(usage("targets=0: expected 1 or more"));
    }
    let request = rigport_pipeline::cloth::ClothRequest {
        garment,
        pins,
        clip,
        fps: fps.map(|f| options::positive("fps", f)).transpose()?,
        seconds,
        substeps,
        thickness,
        preroll,
        collide_all,
        allow_unstable,
        json,
        targets,
        output,
    };
    run(py, |p| rigport_pipeline::cloth(&input, &request, p))
}

/// `rigport render`: pictures of the posed, skinned rig (.png, .gif or .apng): `frames`
/// ("A..B"), `size` ("WxH"), `view` ("front", "side", "top", "three-quarter"), `camera`
/// ("ortho" or "perspective"), `skinning` ("lbs", "dqs" or "both", side by side).
#[pyfunction]
#[pyo3(signature = (
    input, output, *, clip=None, fps=None, frames=None, size="512x512", view="front",
    camera="ortho", handles=None, skinning=None, skeleton=true, frame_counter=true
))]
#[allow(clippy::too_many_arguments)] // one keyword argument per CLI option
fn render(
    py: Python<'_>,
    input: &Bound<'_, PyAny>,
    output: PathBuf,
    clip: Option<String>,
    fps: Option<f32>,
    frames: Option<String>,
    size: &str,
    view: &str,
    camera: &str,
    handles: Option<PathBuf>,
    skinning: Option<String>,
    skeleton: bool,
    frame_counter: bool,
) -> PyResult<Report> {
    let input = input_of(input)?;
    let (width, height) = parsed("size", size, render_pipeline::picture_size(size))?;
    let view = match view {
        "front" => View::Front,
        "side" => View::Side,
        "top" => View::Top,
        "three-quarter" | "three_quarter" => View::ThreeQuarter,
        other => {
            return Err(usage(format!(
                "view={other:?}: expected \"front\", \"side\", \"top\" or \"three-quarter\""
            )));
        }
    };
    let projection = match camera {
        "ortho" => Projection::Orthographic,
        "perspective" => Projection::PERSPECTIVE,
        other => {
            return Err(usage(format!(
                "camera={other:?}: expected \"ortho\" or \"perspective\""
            )));
        }
    };
    let frames = match &frames {
        None => None,
        Some(text) => Some(parsed(
            "frames",
            text,
            render_pipeline::FrameRange::from_str(text),
        )?),
    };
    let skinning = match &skinning {
        None => None,
        Some(text) => Some(parsed(
            "skinning",
            text,
            render_pipeline::skinning_methods(text),
        )?),
    };
    let request = render_pipeline::RenderRequest {
        options: RenderOptions {
            width,
            height,
            view,
            projection,
            skinning: &[],
            skeleton,
            frame_counter,
        },
        skinning,
        clip,
        fps: fps.map(|f| options::positive("fps", f)).transpose()?,
        frames,
        handles,
        output,
    };
    run(py, |p| rigport_pipeline::render(&input, &request, p))
}

/// `rigport skin`: a mesh and a skeleton (`input`) skinned with automatic weights (bone
/// heat), written to `output` (`.out`: a Pinocchio `attachment.out`); the skeleton placed
/// in the mesh's space by `skeleton_offset` (x, y, z) after `skeleton_scale`. Keyword
/// options: those of `Asset.write` but root motion.
#[pyfunction]
#[pyo3(signature = (input, output, *, skeleton_offset=None, skeleton_scale=None, **options))]
fn skin(
    py: Python<'_>,
    input: &Bound<'_, PyAny>,
    output: PathBuf,
    skeleton_offset: Option<[f32; 3]>,
    skeleton_scale: Option<f32>,
    options: Option<&Bound<'_, PyDict>>,
) -> PyResult<Report> {
    let input = input_of(input)?;
    let (output, _) = write_options(output, options, false)?;
    let placement = rigport_pipeline::skin::Placement {
        offset: skeleton_offset
            .map(rigport_model::glam::Vec3::from)
            .unwrap_or_default(),
        scale: match skeleton_scale {
            Some(s) => options::positive("skeleton_scale", s)?,
            None => 1.0,
        },
    };
    let options = rigport_pipeline::skin::SkinOptions { output, placement };
    run(py, |p| rigport_pipeline::skin(&input, &options, p))
}

/// `rigport verify`: whether `candidate` moves as `reference` does (joints and skinned
/// points over `clip`, or every clip with `all_clips`, sampled at `fps` or at the keys
/// with `at_keys`), within `tol` of the reference's size. `Report.passed` says; a picture
/// of the worst frame with `picture` (.png).
#[pyfunction]
#[pyo3(signature = (
    reference, candidate, *, motion=Vec::new(), clip=None, all_clips=false, fps=None,
    at_keys=false, tol=None, json=false, picture=None
))]
#[allow(clippy::too_many_arguments)] // one keyword argument per CLI option
fn verify(
    py: Python<'_>,
    reference: PathBuf,
    candidate: PathBuf,
    motion: Vec<PathBuf>,
    clip: Option<String>,
    all_clips: bool,
    fps: Option<f32>,
    at_keys: bool,
    tol: Option<f64>,
    json: bool,
    picture: Option<PathBuf>,
) -> PyResult<Report> {
    use rigport_pipeline::verify::{Clips, DEFAULT_TOLERANCE, Times, VerifyOptions};
    if clip.is_some() && all_clips {
        return Err(usage("give clip or all_clips, not both"));
    }
    if fps.is_some() && at_keys {
        return Err(usage("give fps or at_keys, not both"));
    }
    let fps = fps.map(|f| options::positive("fps", f)).transpose()?;
    let options = VerifyOptions {
        clips: Clips::from_flags(clip.as_deref(), all_clips),
        times: Times::from_flags(fps, at_keys),
        tolerance: tol.unwrap_or(DEFAULT_TOLERANCE),
        json,
        picture,
        ..VerifyOptions::new(Input::new(vec![candidate]))
    };
    let mut reference = Input::new(vec![reference]);
    reference.files.motions = motion;
    let progress = PyProgress::default();
    let result = py.detach(|| rigport_pipeline::verify(&reference, &options, &progress));
    let verdict = result.map_err(|e| progress.error(py, &e))?;
    Ok(Report::new(verdict.report, &progress).with_verdict(verdict.passed))
}
