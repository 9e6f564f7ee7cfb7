//! Splitting N cases into Slurm job arrays. Sites cap both the number of tasks and the largest
//! task index of an array (`MaxArraySize`, often ~1000), so every array is numbered from 0 and
//! carries an offset into the global task list instead of using `--array=1000-1999`.

use super::{ExecResult, ExecutorError};
use std::ops::Range;

/// One `sbatch --array=0-(tasks-1)` submission.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct ArraySubmission {
    /// Global index of this array's task 0: worker task = offset + `SLURM_ARRAY_TASK_ID`.
    pub offset: usize,
    pub tasks: usize,
    /// The cases its tasks cover, contiguous.
    pub cases: Range<usize>,
}

/// The cases of global task `task` when `n_cases` are packed `cases_per_task` to a task
/// (empty past the end). `cases_per_task` must be ≥ 1.
pub fn task_cases(n_cases: usize, cases_per_task: usize, task: usize) -> Range<usize> {
    let start = task.saturating_mul(cases_per_task).min(n_cases);
    let end = start.saturating_add(cases_per_task).min(n_cases);
    start..end
}

/// Arrays covering `n_cases`: `cases_per_task` cases per task (the last task may have fewer),
/// at most `max_array` tasks per array. No cases, no arrays.
pub fn plan_arrays(
    n_cases: usize,
    cases_per_task: usize,
    max_array: usize,
) -> ExecResult<Vec<ArraySubmission>> {
    if cases_per_task == 0 {
        return Err(ExecutorError::InvalidPlan(
            "cases per task must be at least 1".into(),
        ));
    }
    if max_array == 0 {
        return Err(ExecutorError::InvalidPlan(
            "max array size must be at least 1".into(),
        ));
    }
    let total_tasks = n_cases.div_ceil(cases_per_task);
    let mut arrays = Vec::with_capacity(total_tasks.div_ceil(max_array));
    let mut offset = 0;
    while offset < total_tasks {
        let tasks = max_array.min(total_tasks - offset);
        let first = task_cases(n_cases, cases_per_task, offset);
        let last = task_cases(n_cases, cases_per_task, offset + tasks - 1);
        arrays.push(ArraySubmission {
            offset,
            tasks,
            cases: first.start..last.end,
        });
        offset += tasks;
    }
    Ok(arrays)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every case in exactly one task of exactly one array, in order, within the limits.
    fn check_cover(n: usize, per: usize, max: usize) -> Vec<ArraySubmission> {
        let arrays = plan_arrays(n, per, max).unwrap();
        let mut next_case = 0;
        let mut next_task = 0;
        for a in &arrays {
            assert!(a.tasks >= 1 && a.tasks <= max, "{a:?}");
            assert_eq!(a.offset, next_task);
            assert_eq!(a.cases.start, next_case);
            for t in 0..a.tasks {
                let r = task_cases(n, per, a.offset + t);
                assert_eq!(r.start, next_case);
                assert!(!r.is_empty() && r.len() <= per, "{r:?}");
                next_case = r.end;
            }
            assert_eq!(a.cases.end, next_case);
            next_task += a.tasks;
        }
        assert_eq!(next_case, n);
        arrays
    }

    #[test]
    fn ten_thousand_cases_fit_the_array_limit() {
        // 1 case per task: 10,000 tasks → ten full arrays of 1000.
        let a = check_cover(10_000, 1, 1000);
        assert_eq!(a.len(), 10);
        assert!(a.iter().all(|s| s.tasks == 1000));
        assert_eq!(a[9].offset, 9000);
        assert_eq!(a[9].cases, 9000..10_000);
        // 25 per task: 400 tasks, one array.
        let a = check_cover(10_000, 25, 1000);
        assert_eq!(
            a,
            vec![ArraySubmission {
                offset: 0,
                tasks: 400,
                cases: 0..10_000
            }]
        );
        // 7 per task, arrays of 300: 1429 tasks (last has 4 cases) → 300×4 + 229.
        let a = check_cover(10_000, 7, 300);
        assert_eq!(a.len(), 5);
        assert_eq!(a[4].tasks, 229);
        assert_eq!(task_cases(10_000, 7, 1428), 9996..10_000);
        // A site with MaxArraySize 100 (pitt-crc/user-manual#59).
        let a = check_cover(10_000, 3, 100);
        assert_eq!(a.len(), 34);
        assert_eq!(a[33].tasks, 34);
    }

    #[test]
    fn small_and_edge_plans() {
        assert!(plan_arrays(0, 5, 10).unwrap().is_empty());
        assert_eq!(
            check_cover(1, 5, 10),
            vec![ArraySubmission {
                offset: 0,
                tasks: 1,
                cases: 0..1
            }]
        );
        check_cover(10, 10, 1);
        check_cover(11, 10, 1);
        check_cover(997, 13, 7);
        assert_eq!(task_cases(5, 2, 7), 5..5);
        assert!(matches!(
            plan_arrays(5, 0, 10),
            Err(ExecutorError::InvalidPlan(_))
        ));
        assert!(matches!(
            plan_arrays(5, 1, 0),
            Err(ExecutorError::InvalidPlan(_))
        ));
    }
}
