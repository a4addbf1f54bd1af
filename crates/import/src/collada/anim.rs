//! `<library_animations>`: every `<channel>` (in nested `<animation>`s too) with its
//! `<sampler>`, its target resolved to a node's transform element (a whole value or one
//! component) or to a morph controller's weights, and each sampler evaluated exactly as
//! COLLADA 1.4.1 §4 ("Curve interpolation") defines:
//!
//! - `STEP` holds a key's value, `LINEAR` interpolates each value linearly (a `<rotate>`
//!   angle as an angle, so a turn of several revolutions between two keys is kept);
//! - `BEZIER` uses the `OUT_TANGENT` of a key and the `IN_TANGENT` of the next as control
//!   points: 2D tangents (time, value) are solved for the curve parameter at the time, 1D
//!   tangents take the parameter linear in time; `HERMITE` uses them as slopes per unit of
//!   the parameter. Missing tangents read as `LINEAR`.
//!
//! Targets: `node/sid`, `node/sid.X|.Y|.Z|.ANGLE`, `node/sid(i)` and `node/sid(row)(col)`
//! (a matrix element, row-major as the file writes it), `node/child-sid/.../sid`; and a
//! morph controller's `MORPH_WEIGHT` source (or its array) by id, `(i)` for one target.

use rigport_model::Warning;

use super::scene::Scene;
use super::transform::Kind;
use super::xml::{child, children, Doc, Node, Source};
use crate::ImportError;

/// How a key interpolates to the next.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum Interp {
    Step,
    Linear,
    Bezier,
    Hermite,
}

/// A `<sampler>`: key times, values (`stride` per key), per-key interpolation, tangents.
pub(super) struct Sampler {
    pub(super) times: Vec<f64>,
    pub(super) stride: usize,
    values: Vec<f64>,
    pub(super) interp: Vec<Interp>,
    in_tangent: Option<Source>,
    out_tangent: Option<Source>,
}

/// What a channel animates.
#[derive(Clone, Debug, PartialEq)]
pub(super) enum Target {
    /// Transform element `element` of scene node `node`: its whole value, or one value.
    Transform {
        node: usize,
        element: usize,
        component: Option<usize>,
    },
    /// The weights of the morph controller with this `id`: all, or target `index`.
    Morph {
        controller: String,
        index: Option<usize>,
    },
}

/// One channel.
pub(super) struct Channel<'a, 'i> {
    pub(super) target: Target,
    pub(super) sampler: Sampler,
    /// The `<animation>` elements it is inside (innermost first), for clips.
    pub(super) animations: Vec<Node<'a, 'i>>,
}

/// Every channel of the document, in document order; a channel whose target is not a
/// node transform or morph weight is left out with a warning.
///
/// # Errors
/// A missing sampler or source, a value count that does not fit its target, key times
/// that go back.
pub(super) fn read<'a, 'i>(
    doc: &Doc<'a, 'i>,
    scene: &Scene,
    warnings: &mut Vec<Warning>,
) -> Result<Vec<Channel<'a, 'i>>, ImportError> {
    let mut out = Vec::new();
    let Some(library) = child(doc.root(), "library_animations") else {
        return Ok(out);
    };
    for channel in library
        .descendants()
        .filter(|n| n.tag_name().name() == "channel")
    {
        let path = channel.attribute("target").unwrap_or("");
        let Some(target) = resolve(doc, scene, path) else {
            warnings.push(Warning::Incomplete {
                location: doc.at(channel).to_string(),
                message: format!(
                    "the channel's target {path:?} is not a node transform or morph weight \
                     rigport reads: it is not imported"
                ),
            });
            continue;
        };
        let sampler = read_sampler(doc, doc.link(channel, "source", "sampler")?)?;
        let expected = match &target {
            Target::Transform {
                node,
                element,
                component: None,
            } => Some(scene.nodes[*node].transforms[*element].kind.len()),
            Target::Transform { .. } | Target::Morph { index: Some(_), .. } => Some(1),
            Target::Morph { index: None, .. } => None,
        };
        if let Some(n) = expected.filter(|&n| n != sampler.stride) {
            return Err(ImportError::count(
                doc.at(channel),
                "values per key in its sampler's OUTPUT",
                sampler.stride,
                n,
            ));
        }
        let animations = channel
            .ancestors()
            .filter(|a| a.tag_name().name() == "animation")
            .collect();
        out.push(Channel {
            target,
            sampler,
            animations,
        });
    }
    Ok(out)
}

/// A channel's target path resolved (`None`: not one rigport reads).
fn resolve(doc: &Doc, scene: &Scene, path: &str) -> Option<Target> {
    let mut steps = path.split('/');
    let first = steps.next()?;
    let rest: Vec<&str> = steps.collect();
    let Some(node) = scene.by_id(first) else {
        // Morph weights: the MORPH_WEIGHT source or its array, by id.
        let (id, index) = split_selector(first);
        let element = doc.by_id(id)?;
        let controller = element
            .ancestors()
            .find(|a| a.tag_name().name() == "controller")?;
        child(controller, "morph")?;
        return Some(Target::Morph {
            controller: controller.attribute("id")?.to_string(),
            index: index.first().copied(),
        });
    };
    let (last, inner) = rest.split_last()?;
    let mut at = node;
    for sid in inner {
        at = scene.sid_below(at, sid)?;
    }
    let (sid, selector) = split_member(last);
    let element = scene.nodes[at]
        .transforms
        .iter()
        .position(|t| t.sid.as_deref() == Some(sid))?;
    let kind = scene.nodes[at].transforms[element].kind;
    let component = match selector {
        Selector::Whole => None,
        Selector::Member(m) => Some(kind.member(m)?),
        Selector::Index(i) if kind == Kind::Matrix && i.len() == 2 => Some(i[0] * 4 + i[1]),
        Selector::Index(i) if i.len() == 1 && i[0] < kind.len() => Some(i[0]),
        Selector::Index(_) => return None,
    };
    Some(Target::Transform {
        node: at,
        element,
        component,
    })
}

enum Selector<'s> {
    Whole,
    Member(&'s str),
    Index(Vec<usize>),
}

/// `sid.MEMBER`, `sid(i)(j)` or `sid`.
fn split_member(step: &str) -> (&str, Selector<'_>) {
    if let Some((sid, member)) = step.split_once('.') {
        return (sid, Selector::Member(member));
    }
    let (sid, index) = split_selector(step);
    if index.is_empty() {
        (sid, Selector::Whole)
    } else {
        (sid, Selector::Index(index))
    }
}

/// `name(i)(j)...` as the name and its indices.
fn split_selector(step: &str) -> (&str, Vec<usize>) {
    let Some(open) = step.find('(') else {
        return (step, Vec::new());
    };
    let index = step[open..]
        .split(['(', ')'])
        .filter(|s| !s.is_empty())
        .filter_map(|s| s.trim().parse().ok())
        .collect();
    (&step[..open], index)
}

fn read_sampler(doc: &Doc, sampler: Node) -> Result<Sampler, ImportError> {
    let source = |semantic: &str| -> Result<Option<(Node, Source)>, ImportError> {
        match children(sampler, "input").find(|i| i.attribute("semantic") == Some(semantic)) {
            None => Ok(None),
            Some(i) => {
                let node = doc.link(i, "source", "source")?;
                Ok(Some((node, doc.source(node)?)))
            }
        }
    };
    let (input_node, input) =
        source("INPUT")?.ok_or_else(|| doc.invalid(sampler, "has no INPUT"))?;
    let (output_node, output) =
        source("OUTPUT")?.ok_or_else(|| doc.invalid(sampler, "has no OUTPUT"))?;
    if output.count != input.count {
        return Err(ImportError::count(
            doc.at(output_node),
            "keys",
            output.count,
            input.count,
        ));
    }
    let times: Vec<f64> = (0..input.count).map(|k| input.float(k, 0)).collect();
    if let Some(k) = times.windows(2).position(|w| w[1] < w[0]) {
        return Err(doc.invalid(
            input_node,
            format!(
                "key time {} comes after {}: times must not go back",
                times[k + 1],
                times[k]
            ),
        ));
    }
    let stride = output.stride;
    let values = (0..output.count)
        .flat_map(|k| (0..stride).map(move |c| (k, c)))
        .map(|(k, c)| output.float(k, c))
        .collect();
    let interp = match source("INTERPOLATION")? {
        None => vec![Interp::Linear; times.len()],
        Some((_, names)) => (0..times.len())
            .map(|k| match names.name(k).unwrap_or("LINEAR") {
                "STEP" => Interp::Step,
                "BEZIER" => Interp::Bezier,
                "HERMITE" => Interp::Hermite,
                _ => Interp::Linear,
            })
            .collect(),
    };
    let tangent = |semantic| -> Result<Option<Source>, ImportError> {
        Ok(source(semantic)?
            .map(|(_, s)| s)
            .filter(|s| s.count == times.len() && (s.stride == stride || s.stride == 2 * stride)))
    };
    Ok(Sampler {
        in_tangent: tangent("IN_TANGENT")?,
        out_tangent: tangent("OUT_TANGENT")?,
        times,
        stride,
        values,
        interp,
    })
}

impl Sampler {
    /// Value `c` at key `k`.
    fn value(&self, k: usize, c: usize) -> f64 {
        self.values.get(k * self.stride + c).copied().unwrap_or(0.0)
    }

    /// The key interval holding `t`: `Some(k)` when `times[k] <= t < times[k + 1]`.
    pub(super) fn segment(&self, t: f64) -> Option<usize> {
        let n = self.times.len();
        if n < 2 || t < self.times[0] || t >= self.times[n - 1] {
            return None;
        }
        Some(self.times.partition_point(|&x| x <= t) - 1)
    }

    /// The values at time `t` (held before the first key and after the last).
    pub(super) fn sample(&self, t: f64, out: &mut Vec<f64>) {
        out.clear();
        let n = self.times.len();
        if n == 0 {
            out.resize(self.stride, 0.0);
            return;
        }
        let Some(k) = self.segment(t) else {
            let k = if t < self.times[0] { 0 } else { n - 1 };
            out.extend((0..self.stride).map(|c| self.value(k, c)));
            return;
        };
        let (t0, t1) = (self.times[k], self.times[k + 1]);
        let span = t1 - t0;
        let s = if span > 0.0 { (t - t0) / span } else { 0.0 };
        for c in 0..self.stride {
            let (p0, p1) = (self.value(k, c), self.value(k + 1, c));
            let v = match (self.interp[k], &self.out_tangent, &self.in_tangent) {
                (Interp::Step, ..) => p0,
                (Interp::Bezier, Some(out_t), Some(in_t)) => {
                    self.bezier(out_t, in_t, k, c, t, s, (t0, t1), (p0, p1))
                }
                (Interp::Hermite, Some(out_t), Some(in_t)) => {
                    let (m0, m1) = (out_t.float(k, c), in_t.float(k + 1, c));
                    let (s2, s3) = (s * s, s * s * s);
                    (2.0 * s3 - 3.0 * s2 + 1.0) * p0
                        + (s3 - 2.0 * s2 + s) * m0
                        + (-2.0 * s3 + 3.0 * s2) * p1
                        + (s3 - s2) * m1
                }
                _ => p0 + (p1 - p0) * s,
            };
            out.push(v);
        }
    }

    /// A cubic Bezier segment's value: with 2D tangents the curve's parameter is solved
    /// from the time (bisection: the time curve is monotone for valid tangents), with 1D
    /// tangents it is `s`.
    #[allow(clippy::too_many_arguments)]
    fn bezier(
        &self,
        out_t: &Source,
        in_t: &Source,
        k: usize,
        c: usize,
        t: f64,
        s: f64,
        (t0, t1): (f64, f64),
        (p0, p1): (f64, f64),
    ) -> f64 {
        let cubic = |a: f64, b: f64, cc: f64, d: f64, u: f64| {
            let v = 1.0 - u;
            v * v * v * a + 3.0 * v * v * u * b + 3.0 * v * u * u * cc + u * u * u * d
        };
        if out_t.stride == 2 * self.stride {
            let (ct0, cv0) = (out_t.float(k, 2 * c), out_t.float(k, 2 * c + 1));
            let (ct1, cv1) = (in_t.float(k + 1, 2 * c), in_t.float(k + 1, 2 * c + 1));
            let (mut lo, mut hi) = (0.0, 1.0);
            for _ in 0..60 {
                let mid = 0.5 * (lo + hi);
                if cubic(t0, ct0, ct1, t1, mid) < t {
                    lo = mid;
                } else {
                    hi = mid;
                }
            }
            cubic(p0, cv0, cv1, p1, 0.5 * (lo + hi))
        } else {
            cubic(p0, out_t.float(k, c), in_t.float(k + 1, c), p1, s)
        }
    }
}
