//! Memory budgets: a request's allocation is estimated and checked *before* it is made, so
//! a huge input (an AMC of 10^7 frames, a sample rate of 10^9 per second) is refused with
//! a message that names the size and the limit instead of aborting the process when an
//! allocation fails.
//!
//! The estimates live beside the code that allocates (importers, samplers, writers); this
//! module holds the limit, the check and the wording. Sizes are bytes; "GB" is 10^9.

use std::fmt;

/// The most memory a run may plan to use.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct MemoryBudget {
    /// The limit in bytes.
    pub limit: u64,
    /// Where the limit came from, for messages (e.g. `"--max-memory"`).
    pub origin: &'static str,
}

impl MemoryBudget {
    /// No limit (library callers that manage memory themselves).
    pub const UNLIMITED: Self = Self {
        limit: u64::MAX,
        origin: "no limit",
    };

    /// This budget shared by `workers` jobs in flight at once: each gets an equal part, so
    /// that together they stay within the whole; `origin` says so in messages. One worker
    /// (or none) keeps the whole budget and its origin.
    pub fn shared_by(self, workers: usize, origin: &'static str) -> Self {
        match workers as u64 {
            0 | 1 => self,
            n => Self {
                limit: self.limit / n,
                origin,
            },
        }
    }

    /// `Ok` when `needed` bytes fit the limit; otherwise an [`OverBudget`] naming `what`.
    ///
    /// # Errors
    /// `needed > self.limit`.
    pub fn check(&self, what: impl fmt::Display, needed: u64) -> Result<(), OverBudget> {
        if needed <= self.limit {
            return Ok(());
        }
        Err(OverBudget {
            what: what.to_string(),
            needed,
            limit: self.limit,
            origin: self.origin,
        })
    }
}

/// A request that would need more memory than the budget allows.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
#[error(
    "{what} needs about {} of memory, over the limit of {} ({origin})",
    format_bytes(*needed),
    format_bytes(*limit)
)]
pub struct OverBudget {
    /// What needs the memory, e.g. `writing 10000000 frames of 2 joints as USD text`.
    pub what: String,
    /// Estimated bytes.
    pub needed: u64,
    /// The limit in bytes.
    pub limit: u64,
    /// Where the limit came from.
    pub origin: &'static str,
}

/// `bytes` for people: `512 B`, `3.4 MB`, `5.7 GB` (powers of 1000).
pub fn format_bytes(bytes: u64) -> String {
    const UNITS: [&str; 6] = ["B", "kB", "MB", "GB", "TB", "PB"];
    let mut value = bytes as f64;
    let mut unit = 0;
    while value >= 1000.0 && unit + 1 < UNITS.len() {
        value /= 1000.0;
        unit += 1;
    }
    if unit == 0 {
        format!("{bytes} B")
    } else {
        format!("{value:.1} {}", UNITS[unit])
    }
}

/// Parses a size: a number of bytes with an optional unit `k`, `M`, `G`, `T` (powers of
/// 1000, `B` optional: `2G`, `2GB`, `500M`), or `Ki`, `Mi`, `Gi`, `Ti` (powers of 1024:
/// `1.5GiB`). `None` for anything else, zero, or a size over `u64::MAX`.
pub fn parse_bytes(text: &str) -> Option<u64> {
    let text = text.trim();
    let split = text
        .find(|c: char| !(c.is_ascii_digit() || c == '.'))
        .unwrap_or(text.len());
    let (number, unit) = text.split_at(split);
    let number: f64 = number.parse().ok()?;
    let unit = unit.trim();
    let unit = unit
        .strip_suffix('B')
        .or_else(|| unit.strip_suffix('b'))
        .unwrap_or(unit);
    let scale: f64 = match unit {
        "" => 1.0,
        "k" | "K" => 1e3,
        "M" | "m" => 1e6,
        "G" | "g" => 1e9,
        "T" | "t" => 1e12,
        "Ki" => 1024.0,
        "Mi" => 1024.0 * 1024.0,
        "Gi" => 1024.0 * 1024.0 * 1024.0,
        "Ti" => 1024.0 * 1024.0 * 1024.0 * 1024.0,
        _ => return None,
    };
    let bytes = (number * scale).round();
    (bytes.is_finite() && bytes >= 1.0 && bytes < u64::MAX as f64).then_some(bytes as u64)
}

/// `a * b` in `u64`, saturating (estimates of absurd requests stay absurd, not wrapped).
pub fn mul(a: usize, b: usize) -> u64 {
    (a as u64).saturating_mul(b as u64)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_shared_budget_splits_and_says_so() {
        let whole = MemoryBudget {
            limit: 2_000_000_000,
            origin: "given",
        };
        let part = whole.shared_by(4, "given, shared by 4");
        assert_eq!(
            (part.limit, part.origin),
            (500_000_000, "given, shared by 4")
        );
        assert_eq!(whole.shared_by(1, "unused"), whole);
    }

    #[test]
    fn sizes_parse_with_decimal_and_binary_units() {
        assert_eq!(parse_bytes("2G"), Some(2_000_000_000));
        assert_eq!(parse_bytes("2GB"), Some(2_000_000_000));
        assert_eq!(parse_bytes("500M"), Some(500_000_000));
        assert_eq!(parse_bytes("1.5GiB"), Some(1_610_612_736));
        assert_eq!(parse_bytes("4096"), Some(4096));
        assert_eq!(parse_bytes(" 3 k "), Some(3000));
        for bad in ["", "G", "-1G", "0", "1X", "1e400", "nanG", "2 G B"] {
            assert_eq!(parse_bytes(bad), None, "{bad:?}");
        }
    }

    #[test]
    fn the_check_names_the_request_size_and_limit() {
        let budget = MemoryBudget {
            limit: 2_000_000_000,
            origin: "--max-memory",
        };
        assert!(budget.check("a small thing", 1_000).is_ok());
        let err = budget
            .check("writing 10000000 frames as USD text", 5_700_000_000)
            .unwrap_err()
            .to_string();
        assert!(err.contains("writing 10000000 frames as USD text"), "{err}");
        assert!(err.contains("5.7 GB") && err.contains("2.0 GB"), "{err}");
        assert!(err.contains("(--max-memory)"), "the origin: {err}");
    }

    #[test]
    fn estimates_saturate() {
        assert_eq!(mul(usize::MAX, usize::MAX), u64::MAX);
        assert_eq!(format_bytes(999), "999 B");
        assert_eq!(format_bytes(1_500_000), "1.5 MB");
    }
}
