//! `combine`'s report: one row per clip (its source, how it came onto the rig, its frames
//! and duration, the worst foot slide without and with planting), as a table or JSON.

use serde_json::{Value, json};

/// How a clip came onto the rig.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum How {
    /// The motion's skeleton is the rig's: its tracks as they are.
    Taken,
    /// Retargeted from another skeleton.
    Retargeted,
}

impl How {
    fn label(self) -> &'static str {
        match self {
            How::Taken => "taken",
            How::Retargeted => "retargeted",
        }
    }
}

/// One clip of the result.
#[derive(Clone, Debug)]
pub(crate) struct Row {
    /// The clip's name in the output.
    pub name: String,
    /// The file it came from.
    pub source: String,
    /// Its name there.
    pub source_clip: String,
    /// Taken or retargeted.
    pub how: How,
    /// Key times (frames).
    pub frames: usize,
    /// Seconds.
    pub duration_s: f32,
    /// The worst foot slide during contacts without planting and with it, in rig heights
    /// (`None` when no foot was found or the clip is too short to measure).
    pub slide: Option<(f32, f32)>,
    /// Whether the written clip has its feet planted.
    pub planted: bool,
}

/// The rows as a table, one line each.
pub(crate) fn summary(rows: &[Row]) -> String {
    let mut text = format!(
        "{} clips; foot slide in rig heights, worst over contacts\n{:<24} {:<10} {:>7} {:>9} {:>11} {:>11}  source\n",
        rows.len(),
        "clip",
        "how",
        "frames",
        "seconds",
        "unplanted",
        "planted"
    );
    for r in rows {
        let (without, with) = match r.slide {
            Some((a, b)) => (format!("{a:.4}"), format!("{b:.4}")),
            None => ("-".into(), "-".into()),
        };
        let with = if r.planted { format!("{with}*") } else { with };
        text.push_str(&format!(
            "{:<24} {:<10} {:>7} {:>9.3} {:>11} {:>11}  {}\n",
            r.name,
            r.how.label(),
            r.frames,
            r.duration_s,
            without,
            with,
            r.source
        ));
    }
    if rows.iter().any(|r| r.planted) {
        text.push_str("* written with the feet planted\n");
    }
    text
}

/// The rows as JSON: `[{"clip", "source", "source_clip", "how", "frames", "duration_s",
/// "slide_unplanted", "slide_planted", "planted"}]`.
pub(crate) fn json(rows: &[Row]) -> Value {
    let rows: Vec<Value> = (rows.iter())
        .map(|r| {
            json!({"clip": r.name, "source": r.source, "source_clip": r.source_clip,
                "how": r.how.label(), "frames": r.frames, "duration_s": r.duration_s,
                "slide_unplanted": r.slide.map(|s| s.0), "slide_planted": r.slide.map(|s| s.1),
                "planted": r.planted})
        })
        .collect();
    Value::Array(rows)
}
