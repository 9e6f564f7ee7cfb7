//! The part every reader shares: channels arrive in batches (parts of polars' reads, HDF5 hyperslabs),
//! are checked and appended to the output vectors, and the time column is reduced on the fly
//! (first, last, count, extreme steps) so it is never held in memory.

/// One column of a batch; `nulls[i]` marks a missing value (empty or unparsable cell).
pub(super) struct Col<'a> {
    pub values: &'a [f64],
    pub nulls: Option<&'a [bool]>,
}

impl<'a> Col<'a> {
    pub fn new(values: &'a [f64]) -> Self {
        Col {
            values,
            nulls: None,
        }
    }

    fn clean(&self) -> bool {
        self.nulls.is_none() && self.values.iter().all(|x| x.is_finite())
    }

    fn missing(&self, i: usize) -> bool {
        self.nulls.is_some_and(|n| n[i])
    }

    fn bad(&self, i: usize) -> bool {
        self.missing(i) || !self.values[i].is_finite()
    }
}

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) enum Channel {
    Time,
    Velocity,
    Index,
}

/// The first run of rows with a missing or non-finite value in any channel.
#[derive(Debug, Clone)]
pub(super) struct BadRun {
    pub start: usize,
    pub len: usize,
    /// A good row followed the run (else it reaches the end of what was read).
    pub ended: bool,
    /// Channels bad in the first row of the run.
    pub channels: Vec<Channel>,
    /// The first row of the run has a missing value (not only NaN/inf).
    pub missing: bool,
    /// Every channel of every row of the run is missing (blank lines).
    pub all_missing: bool,
}

#[derive(Debug, Clone, Copy)]
pub(super) enum TimeFault {
    /// `cur` (at `row`) does not exceed the previous value `prev`.
    NonMonotonic { row: usize, prev: f64, cur: f64 },
    /// NaN or infinite time value (standalone time datasets only; in a stream it is a bad row).
    NonFinite { row: usize },
}

/// Streaming reduction of a time (or sample-number) column.
#[derive(Debug, Clone)]
pub(super) struct TimeAcc {
    pub first: f64,
    pub last: f64,
    pub n: usize,
    min_dt: f64,
    min_at: usize,
    max_dt: f64,
    max_at: usize,
    pub fault: Option<TimeFault>,
}

/// Summary of a time column after the stream.
#[derive(Debug, Clone, Copy)]
pub(super) struct TimeStats {
    pub first: f64,
    /// (last − first)/(n − 1): robust against a single jittered step.
    pub mean_dt: f64,
    /// The step that deviates most from `mean_dt` (row of the later sample, step).
    pub worst: (usize, f64),
}

impl Default for TimeAcc {
    fn default() -> Self {
        TimeAcc {
            first: f64::NAN,
            last: f64::NAN,
            n: 0,
            min_dt: f64::INFINITY,
            min_at: 0,
            max_dt: f64::NEG_INFINITY,
            max_at: 0,
            fault: None,
        }
    }
}

impl TimeAcc {
    /// Adds the value of row `row`; `false` once a fault is recorded.
    #[inline]
    pub fn push(&mut self, row: usize, t: f64) -> bool {
        if !t.is_finite() {
            self.fault = Some(TimeFault::NonFinite { row });
            return false;
        }
        if self.n == 0 {
            self.first = t;
        } else {
            let dt = t - self.last;
            if dt <= 0.0 {
                self.fault = Some(TimeFault::NonMonotonic {
                    row,
                    prev: self.last,
                    cur: t,
                });
                return false;
            }
            if dt < self.min_dt {
                self.min_dt = dt;
                self.min_at = row;
            }
            if dt > self.max_dt {
                self.max_dt = dt;
                self.max_at = row;
            }
        }
        self.last = t;
        self.n += 1;
        true
    }

    /// Adds consecutive rows starting at `row0`; `false` once a fault is recorded.
    pub fn push_slice(&mut self, row0: usize, values: &[f64]) -> bool {
        values
            .iter()
            .enumerate()
            .all(|(i, &t)| self.push(row0 + i, t))
    }

    pub fn stats(&self) -> Option<TimeStats> {
        if self.n < 2 {
            return None;
        }
        let mean_dt = (self.last - self.first) / (self.n - 1) as f64;
        let worst = if self.max_dt - mean_dt >= mean_dt - self.min_dt {
            (self.max_at, self.max_dt)
        } else {
            (self.min_at, self.min_dt)
        };
        Some(TimeStats {
            first: self.first,
            mean_dt,
            worst,
        })
    }
}

/// Accumulates the channels of a record batch by batch.
pub(super) struct Stream {
    /// Factor applied to the velocity values (mV → V, mm/s → m/s).
    vel_scale: f64,
    pub velocity: Vec<f64>,
    pub index: Option<Vec<f64>>,
    pub time: Option<TimeAcc>,
    /// Rows consumed so far.
    pub rows: usize,
    pub run: Option<BadRun>,
}

impl Stream {
    pub fn new(vel_scale: f64, has_index: bool, has_time: bool, capacity: usize) -> Self {
        Stream {
            vel_scale,
            velocity: crate::numerics::buffer::sample_buffer(capacity),
            index: has_index.then(|| crate::numerics::buffer::sample_buffer(capacity)),
            time: has_time.then(TimeAcc::default),
            rows: 0,
            run: None,
        }
    }

    /// Whether reading can stop: a bad run has ended or the time column is broken.
    pub fn done(&self) -> bool {
        self.run.as_ref().is_some_and(|r| r.ended)
            || self.time.as_ref().is_some_and(|t| t.fault.is_some())
    }

    /// Appends one batch (all columns the same length); returns `true` when reading can stop.
    pub fn push(&mut self, t: Option<Col>, v: Col, idx: Option<Col>) -> bool {
        if self.done() {
            return true;
        }
        let n = v.values.len();
        let clean = self.run.is_none()
            && v.clean()
            && idx.as_ref().is_none_or(Col::clean)
            && t.as_ref().is_none_or(Col::clean);
        if clean {
            if let Some(acc) = &mut self.time {
                let t = t.as_ref().map_or(&[][..], |c| c.values);
                if !acc.push_slice(self.rows, t) {
                    return true;
                }
            }
            if self.vel_scale == 1.0 {
                self.velocity.extend_from_slice(v.values);
            } else {
                let s = self.vel_scale;
                self.velocity.extend(v.values.iter().map(|x| x * s));
            }
            if let (Some(out), Some(c)) = (&mut self.index, &idx) {
                out.extend_from_slice(c.values);
            }
            self.rows += n;
            return false;
        }
        for i in 0..n {
            let mut bad = Vec::new();
            let mut missing = false;
            let mut all_missing = true;
            for (chan, col) in [
                (Channel::Time, t.as_ref()),
                (Channel::Velocity, Some(&v)),
                (Channel::Index, idx.as_ref()),
            ] {
                if let Some(col) = col {
                    if col.bad(i) {
                        bad.push(chan);
                    }
                    missing |= col.missing(i);
                    all_missing &= col.missing(i);
                }
            }
            let row = self.rows;
            if bad.is_empty() {
                if let Some(run) = &mut self.run {
                    run.ended = true;
                    return true;
                }
                if let (Some(acc), Some(t)) = (&mut self.time, &t) {
                    if !acc.push(row, t.values[i]) {
                        return true;
                    }
                }
                self.velocity.push(v.values[i] * self.vel_scale);
                if let (Some(out), Some(c)) = (&mut self.index, &idx) {
                    out.push(c.values[i]);
                }
            } else {
                match &mut self.run {
                    None => {
                        self.run = Some(BadRun {
                            start: row,
                            len: 1,
                            ended: false,
                            channels: bad,
                            missing,
                            all_missing,
                        })
                    }
                    Some(run) => {
                        run.len += 1;
                        run.all_missing &= all_missing;
                    }
                }
            }
            self.rows += 1;
        }
        false
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn runs_and_time_reduction() {
        let mut s = Stream::new(2.0, true, true, 0);
        let t = [0.0, 1.0, 2.0];
        let v = [1.0, 2.0, 3.0];
        assert!(!s.push(Some(Col::new(&t)), Col::new(&v), Some(Col::new(&v))));
        assert_eq!(s.velocity, vec![2.0, 4.0, 6.0]);
        let t2 = [3.0, 4.0, 5.0, 6.0];
        let v2 = [1.0, f64::NAN, 0.0, 1.0];
        let nulls = [false, false, true, false];
        let idx = Col {
            values: &v2,
            nulls: Some(&nulls),
        };
        // NaN at row 4, null at row 5, then a good row ends the run.
        assert!(s.push(Some(Col::new(&t2)), Col::new(&v2), Some(idx)));
        let run = s.run.clone().unwrap();
        assert_eq!((run.start, run.len, run.ended), (4, 2, true));
        assert_eq!(run.channels, vec![Channel::Velocity, Channel::Index]);
        assert!(!run.missing && !run.all_missing);
        let stats = s.time.as_ref().unwrap().stats().unwrap();
        assert_eq!((stats.first, stats.mean_dt), (0.0, 1.0));

        let mut acc = TimeAcc::default();
        assert!(!acc.push_slice(10, &[0.0, 1.0, 3.0, 3.0]));
        assert!(matches!(
            acc.fault,
            Some(TimeFault::NonMonotonic { row: 13, .. })
        ));
        let mut acc = TimeAcc::default();
        assert!(acc.push_slice(0, &[0.0, 1.0, 2.0, 3.5, 4.0, 5.0]));
        let st = acc.stats().unwrap();
        assert_eq!(st.worst, (3, 1.5));
    }
}
