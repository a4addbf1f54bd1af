//! When a simulation has diverged: the stability limits every output frame is held to.
//!
//! A garment on a moving body stretches a little (its pins follow skin that stretches) and
//! moves as fast as the body plus its own swing. The limits sit well beyond what a
//! converged simulation of cloth gives, and well below what a diverging one reaches (a
//! looped clip jumping back with its root motion reached 638% stretch):
//! - stretch: [`UNSTABLE_STRETCH`] (an edge half again its rest length; the demo's skirt
//!   stays under 10%);
//! - speed: twice the speed of the body's fastest skin point that frame (a garment
//!   reaching out twice a limb's length from its joint turns twice as fast as the limb's
//!   skin) plus [`UNSTABLE_SPEED`] body diagonals per second (a hem whipping at 36 m/s on
//!   a 1.8 m body);
//! - kinetic energy per unit mass: `½ (2 body speed + UNSTABLE_MEAN_SPEED diagonals/s)²`,
//!   the whole garment moving on average that much faster.
//!
//! "The body's fastest skin point" remembers the recent past: the fastest of this frame,
//! and of earlier frames fading with [`BODY_MEMORY`] (a garment thrown by a fast move, or
//! by a looped clip's jump back to its start, keeps flying for a while after the body has
//! slowed down).

use std::fmt;

use super::FrameStats;

/// Largest edge stretch, `(length - rest) / rest`, of a stable simulation.
pub const UNSTABLE_STRETCH: f32 = 0.5;

/// How much faster than twice the body's fastest skin point, in body diagonals per
/// second, a garment vertex of a stable simulation moves at most.
pub const UNSTABLE_SPEED: f32 = 20.0;

/// How much faster than twice the body's fastest skin point, in body diagonals per
/// second, the garment moves on average (root mean square) at most: the kinetic energy
/// limit.
pub const UNSTABLE_MEAN_SPEED: f32 = 5.0;

/// How long, in seconds, the body's speed counts after it (exponential fade).
pub const BODY_MEMORY: f32 = 0.5;

/// The body speed the limits allow for: `current` (units/s), or the previous reference
/// faded over `span` seconds when that is faster.
pub(crate) fn body_reference(previous: f32, current: f32, span: f32) -> f32 {
    current.max(previous * (-span / BODY_MEMORY).exp())
}

/// What went past its limit.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Measure {
    /// The largest edge stretch (a fraction).
    Stretch,
    /// Kinetic energy per unit mass (units²/s²).
    KineticEnergy,
    /// The fastest vertex's speed (units/s).
    Speed,
}

impl fmt::Display for Measure {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            Measure::Stretch => "edge stretch",
            Measure::KineticEnergy => "kinetic energy per unit mass",
            Measure::Speed => "vertex speed",
        })
    }
}

/// The first limit `stats` is past, as (measure, value, limit), for a body of `diagonal`
/// whose fastest skin point moves at `body_speed` (units/s; [`body_reference`]).
pub(crate) fn past_limit(
    stats: &FrameStats,
    diagonal: f32,
    body_speed: f32,
) -> Option<(Measure, f32, f32)> {
    let speed = 2.0 * body_speed + UNSTABLE_SPEED * diagonal;
    let mean = 2.0 * body_speed + UNSTABLE_MEAN_SPEED * diagonal;
    let energy = 0.5 * mean * mean;
    [
        (Measure::Stretch, stats.max_stretch, UNSTABLE_STRETCH),
        (Measure::Speed, stats.max_speed, speed),
        (Measure::KineticEnergy, stats.kinetic_energy, energy),
    ]
    .into_iter()
    // A NaN value is past every limit.
    .find(|&(_, value, limit)| value.is_nan() || value > limit)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn limits_scale_with_the_body() {
        let calm = FrameStats {
            max_stretch: 0.1,
            kinetic_energy: 1.0,
            max_speed: 5.0,
            ..FrameStats::default()
        };
        assert_eq!(past_limit(&calm, 1.8, 0.0), None);
        let torn = FrameStats {
            max_stretch: 6.38,
            ..calm
        };
        assert_eq!(
            past_limit(&torn, 1.8, 0.0),
            Some((Measure::Stretch, 6.38, UNSTABLE_STRETCH))
        );
        let fast = FrameStats {
            max_speed: 327.0,
            ..calm
        };
        assert!(matches!(
            past_limit(&fast, 1.7, 1.0),
            Some((Measure::Speed, _, limit)) if (limit - 36.0).abs() < 1e-4
        ));
        // A body running at 10 units/s carries its garment, swinging: not a divergence.
        let carried = FrameStats {
            kinetic_energy: 200.0,
            max_speed: 30.0,
            ..calm
        };
        assert_eq!(past_limit(&carried, 1.8, 10.0), None);
        let nan = FrameStats {
            kinetic_energy: f32::NAN,
            ..calm
        };
        assert!(past_limit(&nan, 1.8, 0.0).is_some());
    }
}
