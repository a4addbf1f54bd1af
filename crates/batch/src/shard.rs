//! Shards: which items one process of a cluster job runs.
//!
//! Item `k` (its position in manifest order, counted from 0 over the whole manifest after
//! folder expansion) belongs to shard `k mod N`. The rule is by position, not by a hash of
//! the id: shards are balanced to within one item, and a shard's items are easy to list
//! (`k = I, I + N, I + 2N, ...`). Adding items at the end of a manifest keeps every
//! earlier item in its shard; inserting one in the middle moves later items, which a
//! `--resume` run then skips in their new shard anyway (the sidecars live with the
//! outputs, not with the shard).

use std::fmt;

/// One shard of `count`: the items whose position `k` has `k % count == index`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Shard {
    /// This shard, `0..count`.
    pub index: usize,
    /// How many shards there are, at least 1.
    pub count: usize,
}

/// A shard specification that cannot be used.
#[derive(Debug, thiserror::Error, PartialEq, Eq)]
pub enum ShardError {
    /// Not `I/N` with `0 <= I < N`.
    #[error("{source_name} {text:?}: expected I/N with 0 <= I < N, e.g. 0/3")]
    Syntax {
        /// Where the text came from (`--shard` or an environment variable).
        source_name: String,
        /// The text.
        text: String,
    },
    /// An index variable without its count.
    #[error("{index_var} is set but {count_var} is not: set {count_var} to the number of shards")]
    MissingCount {
        /// The index variable.
        index_var: &'static str,
        /// The count variable.
        count_var: &'static str,
    },
}

impl Shard {
    /// Every item: shard 0 of 1.
    pub const ALL: Shard = Shard { index: 0, count: 1 };

    /// Parses `I/N`.
    ///
    /// # Errors
    /// [`ShardError::Syntax`] naming `source_name`.
    pub fn parse(text: &str, source_name: &str) -> Result<Shard, ShardError> {
        let bad = || ShardError::Syntax {
            source_name: source_name.into(),
            text: text.into(),
        };
        let (i, n) = text.split_once('/').ok_or_else(bad)?;
        let index: usize = i.trim().parse().map_err(|_| bad())?;
        let count: usize = n.trim().parse().map_err(|_| bad())?;
        if count == 0 || index >= count {
            return Err(bad());
        }
        Ok(Shard { index, count })
    }

    /// The shard the environment of a cluster engine names, if any:
    /// `JOB_COMPLETION_INDEX` with `JOB_COMPLETIONS` (a Kubernetes Indexed Job sets the
    /// index; the job spec sets the count, see docs/scale.md), else
    /// `SLURM_ARRAY_TASK_ID` with `SLURM_ARRAY_TASK_COUNT` (a Slurm job array; the index is
    /// `(ID - SLURM_ARRAY_TASK_MIN) / SLURM_ARRAY_TASK_STEP`, each 0 and 1 when unset, so
    /// `--array=1-3` and the stepped `--array=0-4:2`, whose tasks 0, 2, 4 are shards 0, 1, 2
    /// of 3, both cover every item; a task ID off the step is an error).
    /// `var` looks a variable up (`|k| std::env::var(k).ok()` in a program).
    ///
    /// # Errors
    /// An index without its count, or values that are not a shard.
    pub fn from_env(var: impl Fn(&str) -> Option<String>) -> Result<Option<Shard>, ShardError> {
        if let Some(index) = var("JOB_COMPLETION_INDEX") {
            let count = var("JOB_COMPLETIONS").ok_or(ShardError::MissingCount {
                index_var: "JOB_COMPLETION_INDEX",
                count_var: "JOB_COMPLETIONS",
            })?;
            let text = format!("{}/{}", index.trim(), count.trim());
            return Shard::parse(&text, "JOB_COMPLETION_INDEX/JOB_COMPLETIONS").map(Some);
        }
        if let Some(id) = var("SLURM_ARRAY_TASK_ID") {
            let count = var("SLURM_ARRAY_TASK_COUNT").ok_or(ShardError::MissingCount {
                index_var: "SLURM_ARRAY_TASK_ID",
                count_var: "SLURM_ARRAY_TASK_COUNT",
            })?;
            let name = "SLURM_ARRAY_TASK_ID/SLURM_ARRAY_TASK_COUNT";
            let bad = || ShardError::Syntax {
                source_name: name.into(),
                text: format!("{id}/{count}"),
            };
            let id: usize = id.trim().parse().map_err(|_| bad())?;
            let min: usize = match var("SLURM_ARRAY_TASK_MIN") {
                Some(m) => m.trim().parse().map_err(|_| bad())?,
                None => 0,
            };
            let step: usize = match var("SLURM_ARRAY_TASK_STEP") {
                Some(m) => m.trim().parse().map_err(|_| bad())?,
                None => 1,
            };
            let offset = id.checked_sub(min).ok_or_else(bad)?;
            if step == 0 || offset % step != 0 {
                return Err(bad());
            }
            let index = offset / step;
            return Shard::parse(&format!("{index}/{}", count.trim()), name).map(Some);
        }
        Ok(None)
    }

    /// `arg` (`I/N`, named `arg_name` in errors) when given, else the environment's
    /// ([`Shard::from_env`]), else every item ([`Shard::ALL`]).
    ///
    /// # Errors
    /// As [`Shard::parse`] and [`Shard::from_env`].
    pub fn resolve(
        arg: Option<&str>,
        arg_name: &str,
        var: impl Fn(&str) -> Option<String>,
    ) -> Result<Shard, ShardError> {
        match arg {
            Some(text) => Shard::parse(text, arg_name),
            None => Ok(Shard::from_env(var)?.unwrap_or(Shard::ALL)),
        }
    }

    /// Whether the item at manifest position `k` belongs to this shard.
    pub fn contains(&self, k: usize) -> bool {
        k % self.count == self.index
    }
}

impl fmt::Display for Shard {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}/{}", self.index, self.count)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn env<'a>(pairs: &'a [(&'a str, &'a str)]) -> impl Fn(&str) -> Option<String> + 'a {
        move |k| {
            pairs
                .iter()
                .find(|(n, _)| *n == k)
                .map(|(_, v)| v.to_string())
        }
    }

    #[test]
    fn parses_and_selects() {
        let s = Shard::parse("1/3", "--shard").unwrap_or(Shard::ALL);
        assert_eq!(s, Shard { index: 1, count: 3 });
        let picked: Vec<usize> = (0..8).filter(|&k| s.contains(k)).collect();
        assert_eq!(picked, [1, 4, 7]);
        for bad in ["3/3", "0/0", "1", "a/2", "-1/2"] {
            assert!(Shard::parse(bad, "--shard").is_err(), "{bad}");
        }
    }

    #[test]
    fn from_kubernetes_and_slurm() {
        let k8s = env(&[("JOB_COMPLETION_INDEX", "2"), ("JOB_COMPLETIONS", "3")]);
        assert_eq!(Shard::from_env(k8s), Ok(Some(Shard { index: 2, count: 3 })));
        let slurm = env(&[
            ("SLURM_ARRAY_TASK_ID", "3"),
            ("SLURM_ARRAY_TASK_COUNT", "3"),
            ("SLURM_ARRAY_TASK_MIN", "1"),
        ]);
        assert_eq!(
            Shard::from_env(slurm),
            Ok(Some(Shard { index: 2, count: 3 }))
        );
        // `--array=0-4:2`: tasks 0, 2 and 4 are the three shards, each item in one.
        let stepped = |id: &'static str| {
            Shard::from_env(env(&[
                ("SLURM_ARRAY_TASK_ID", id),
                ("SLURM_ARRAY_TASK_COUNT", "3"),
                ("SLURM_ARRAY_TASK_MIN", "0"),
                ("SLURM_ARRAY_TASK_MAX", "4"),
                ("SLURM_ARRAY_TASK_STEP", "2"),
            ]))
        };
        let shards: Vec<Shard> = ["0", "2", "4"]
            .into_iter()
            .map(|id| stepped(id).unwrap().unwrap())
            .collect();
        assert_eq!(
            shards
                .iter()
                .map(|s| (s.index, s.count))
                .collect::<Vec<_>>(),
            [(0, 3), (1, 3), (2, 3)]
        );
        for k in 0..20 {
            assert_eq!(
                shards.iter().filter(|s| s.contains(k)).count(),
                1,
                "item {k}"
            );
        }
        assert!(stepped("3").is_err(), "a task off the step");
        let lone = env(&[("JOB_COMPLETION_INDEX", "0")]);
        assert!(matches!(
            Shard::from_env(lone),
            Err(ShardError::MissingCount { .. })
        ));
        assert_eq!(Shard::from_env(env(&[])), Ok(None));
    }
}
