//! Slices of a sweep for cluster array jobs. Shard `i` of `N` runs the
//! runs whose plan index is `i` mod `N`. The first shard to write a
//! results folder records `N` in its `plan.json`; every later shard must
//! agree, and a Slurm array task that names only its index
//! (`SLURM_ARRAY_TASK_ID`, as a task resubmitted alone with `--array=i`
//! does) runs shard `i` of the recorded `N`. The count is never taken
//! from the size of the array, which a resubmission changes.

use serde::{Deserialize, Serialize};

/// One slice of a sweep: runs whose plan index is `index` modulo `count`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub struct Shard {
    /// This shard, from 0.
    pub index: usize,
    /// Number of shards.
    pub count: usize,
}

/// Why a run's shard cannot be settled.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum ShardError {
    /// `--shard` is not `i/N` with `0 ≤ i < N`.
    #[error("shard `{text}`: expected `i/N` with 0 ≤ i < N, e.g. `0/4`")]
    Malformed {
        /// What was given.
        text: String,
    },
    /// The shard count disagrees with the one the folder was started with.
    #[error(
        "this results folder was started as {recorded} shards (its plan.json); `--shard {index}/{given}` would slice the sweep differently: pass `--shard {index}/{recorded}`, or `--force` in a new folder"
    )]
    CountChanged {
        /// The count in `plan.json`.
        recorded: usize,
        /// This shard's index.
        index: usize,
        /// The count given now.
        given: usize,
    },
    /// A Slurm array task whose shard count nothing says.
    #[error(
        "Slurm array task {index}: the number of shards is not known (no plan.json records it yet); pass `--shard {index}/N`, as experiments/slurm/sweep.sbatch does"
    )]
    CountUnknown {
        /// The task's index.
        index: usize,
    },
    /// A task index at or past the recorded count.
    #[error("Slurm array task {index} is not a shard of the {count} this folder was started with")]
    OutOfRange {
        /// The task's index.
        index: usize,
        /// The recorded count.
        count: usize,
    },
}

impl Shard {
    /// Parses `i/N` (0 ≤ i < N).
    ///
    /// # Errors
    /// [`ShardError::Malformed`].
    pub fn parse(text: &str) -> Result<Self, ShardError> {
        let bad = || ShardError::Malformed {
            text: text.to_string(),
        };
        let (i, n) = text.split_once('/').ok_or_else(bad)?;
        let (index, count): (usize, usize) = (
            i.trim().parse().map_err(|_| bad())?,
            n.trim().parse().map_err(|_| bad())?,
        );
        if count == 0 || index >= count {
            return Err(bad());
        }
        Ok(Self { index, count })
    }

    /// Whether this shard runs plan entry `run_index`.
    pub fn owns(&self, run_index: usize) -> bool {
        run_index % self.count == self.index
    }

    /// The shard a run takes: `given` (`--shard i/N`), else shard
    /// `slurm_task` of the count `recorded` in the folder's `plan.json`,
    /// else none (the whole sweep).
    ///
    /// # Errors
    /// [`ShardError::CountChanged`] when `given` disagrees with
    /// `recorded`; [`ShardError::CountUnknown`] or
    /// [`ShardError::OutOfRange`] for a Slurm task without `--shard`.
    pub fn resolve(
        given: Option<Self>,
        slurm_task: Option<usize>,
        recorded: Option<usize>,
    ) -> Result<Option<Self>, ShardError> {
        match (given, slurm_task, recorded) {
            (Some(s), _, Some(n)) if s.count != n => Err(ShardError::CountChanged {
                recorded: n,
                index: s.index,
                given: s.count,
            }),
            (Some(s), _, _) => Ok(Some(s)),
            (None, Some(index), Some(count)) if index < count => Ok(Some(Self { index, count })),
            (None, Some(index), Some(count)) => Err(ShardError::OutOfRange { index, count }),
            (None, Some(index), None) => Err(ShardError::CountUnknown { index }),
            (None, None, _) => Ok(None),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn shard(index: usize, count: usize) -> Shard {
        Shard { index, count }
    }

    #[test]
    fn every_run_belongs_to_exactly_one_shard() {
        for count in 1..6 {
            for run in 0..20 {
                let owners = (0..count).filter(|&i| shard(i, count).owns(run)).count();
                assert_eq!(owners, 1, "run {run} of {count} shards");
            }
        }
        assert_eq!(Shard::parse("2/4"), Ok(shard(2, 4)));
        for bad in ["4/4", "1/0", "x/2", "3"] {
            assert!(Shard::parse(bad).is_err(), "{bad}");
        }
    }

    #[test]
    fn a_first_array_of_n_tasks_records_n_and_a_resubmitted_task_runs_its_own_shard() {
        // The first submission passes the count explicitly.
        assert_eq!(
            Shard::resolve(Some(shard(3, 16)), Some(3), None),
            Ok(Some(shard(3, 16)))
        );
        // `--array=3` alone, resubmitted without `--shard`: shard 3 of the
        // 16 the folder records, whatever the new array's size.
        assert_eq!(
            Shard::resolve(None, Some(3), Some(16)),
            Ok(Some(shard(3, 16)))
        );
        // `--array=0` alone is shard 0 of 16, not the whole sweep as 0/1.
        assert_eq!(
            Shard::resolve(None, Some(0), Some(16)),
            Ok(Some(shard(0, 16)))
        );
        // The same task resubmitted with its `--shard` is accepted too.
        assert_eq!(
            Shard::resolve(Some(shard(3, 16)), Some(3), Some(16)),
            Ok(Some(shard(3, 16)))
        );
    }

    #[test]
    fn a_count_that_changes_or_that_nothing_says_is_refused() {
        assert!(matches!(
            Shard::resolve(Some(shard(0, 1)), Some(0), Some(16)),
            Err(ShardError::CountChanged {
                recorded: 16,
                given: 1,
                ..
            })
        ));
        assert_eq!(
            Shard::resolve(None, Some(2), None),
            Err(ShardError::CountUnknown { index: 2 })
        );
        assert_eq!(
            Shard::resolve(None, Some(16), Some(16)),
            Err(ShardError::OutOfRange {
                index: 16,
                count: 16
            })
        );
        // Outside an array, and without --shard, the whole sweep runs.
        assert_eq!(Shard::resolve(None, None, Some(4)), Ok(None));
        assert_eq!(Shard::resolve(None, None, None), Ok(None));
    }
}
