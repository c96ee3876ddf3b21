//! A series in bounded memory: at most [`BUCKETS`] time buckets, each keeping its first,
//! minimum, maximum and last point; neighbouring buckets merge in pairs when more are
//! needed.

use super::BUCKETS;

#[derive(Clone, Copy, Debug)]
struct Bucket {
    key: i64,
    first: (f64, f64),
    min: (f64, f64),
    max: (f64, f64),
    last: (f64, f64),
    /// Whether the maximum came after the minimum (the order they are drawn in; their
    /// times can be equal, at a step).
    max_after_min: bool,
}

/// A time series in at most [`BUCKETS`] min/max buckets (see the module docs).
#[derive(Debug)]
pub struct Series {
    width: f64,
    buckets: Vec<Bucket>,
    /// Points taken (before decimation).
    pub count: u64,
}

impl Default for Series {
    fn default() -> Self {
        Series {
            width: 0.05,
            buckets: Vec::new(),
            count: 0,
        }
    }
}

impl Series {
    /// Adds a point; times must not go backwards (a later point at an earlier time goes
    /// into the last bucket).
    pub fn push(&mut self, t: f64, v: f64) {
        if !t.is_finite() || !v.is_finite() {
            return;
        }
        self.count += 1;
        loop {
            let key = (t / self.width).floor() as i64;
            let len = self.buckets.len();
            match self.buckets.last_mut() {
                Some(b) if key <= b.key => {
                    if v < b.min.1 {
                        b.min = (t, v);
                        b.max_after_min = false;
                    }
                    if v > b.max.1 {
                        b.max = (t, v);
                        b.max_after_min = true;
                    }
                    b.last = (t, v);
                    return;
                }
                _ if len < BUCKETS => {
                    self.buckets.push(Bucket {
                        key,
                        first: (t, v),
                        min: (t, v),
                        max: (t, v),
                        last: (t, v),
                        max_after_min: false,
                    });
                    return;
                }
                _ => self.halve(),
            }
        }
    }

    /// Doubles the bucket width, merging buckets that fall together.
    fn halve(&mut self) {
        self.width *= 2.0;
        let mut merged: Vec<Bucket> = Vec::with_capacity(BUCKETS);
        for b in self.buckets.drain(..) {
            let key = b.key.div_euclid(2);
            match merged.last_mut() {
                Some(m) if m.key == key => {
                    // `b`'s points all came after `m`'s.
                    let (min, max) = (b.min.1 < m.min.1, b.max.1 > m.max.1);
                    if min {
                        m.min = b.min;
                    }
                    if max {
                        m.max = b.max;
                    }
                    m.max_after_min = match (min, max) {
                        (true, true) => b.max_after_min,
                        (true, false) => false,
                        (false, true) => true,
                        (false, false) => m.max_after_min,
                    };
                    m.last = b.last;
                }
                _ => merged.push(Bucket { key, ..b }),
            }
        }
        self.buckets = merged;
    }

    /// The points to draw, in the order they came: each bucket's first point, its min and
    /// max, and its last point (so steps keep their shape and spikes survive).
    pub fn points(&self) -> Vec<(f64, f64)> {
        let mut out: Vec<(f64, f64)> = Vec::with_capacity(self.buckets.len() * 4);
        for b in &self.buckets {
            let (earlier, later) = if b.max_after_min {
                (b.min, b.max)
            } else {
                (b.max, b.min)
            };
            for p in [b.first, earlier, later, b.last] {
                if out.last() != Some(&p) {
                    out.push(p);
                }
            }
        }
        out
    }

    /// Each bucket's time, for markers (one per bucket).
    pub fn times(&self) -> Vec<f64> {
        self.buckets.iter().map(|b| b.first.0).collect()
    }

    pub(super) fn range(&self) -> Option<(f64, f64)> {
        let lo = self.buckets.iter().map(|b| b.min.1).reduce(f64::min)?;
        let hi = self.buckets.iter().map(|b| b.max.1).reduce(f64::max)?;
        Some((lo, hi))
    }

    pub(super) fn is_empty(&self) -> bool {
        self.buckets.is_empty()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn series_is_bounded_and_keeps_extremes() {
        let mut s = Series::default();
        for i in 0..1_000_000u32 {
            let t = f64::from(i) * 0.01;
            let v = if i == 777_777 { 500.0 } else { (t * 0.1).sin() };
            s.push(t, v);
        }
        assert!(s.buckets.len() <= BUCKETS);
        assert!(s.buckets.len() > BUCKETS / 2);
        let pts = s.points();
        assert!(pts.len() <= 4 * BUCKETS);
        assert!(pts.windows(2).all(|w| w[0].0 <= w[1].0));
        assert!(pts
            .iter()
            .any(|&(t, v)| v == 500.0 && (t - 7777.77).abs() < 1e-6));
        assert_eq!(s.count, 1_000_000);
    }

    /// A point with a time or value that is not a finite number is not taken.
    #[test]
    fn points_that_are_not_finite_are_not_taken() {
        let mut s = Series::default();
        for (t, v) in [
            (f64::NAN, 1.0),
            (1.0, f64::NAN),
            (f64::INFINITY, 1.0),
            (1.0, f64::NEG_INFINITY),
        ] {
            s.push(t, v);
        }
        assert_eq!(s.count, 0);
        assert!(s.is_empty());
        s.push(1.0, 2.0);
        assert_eq!(s.points(), [(1.0, 2.0)]);
        assert_eq!(s.range(), Some((2.0, 2.0)));
    }

    /// A step inside one bucket (0.05 s wide) is drawn where it happened: a bucket's
    /// minimum and maximum are the first points at those values, not the last.
    #[test]
    fn a_step_inside_one_bucket_keeps_its_time() {
        for (before, after) in [(1.0, 0.0), (0.0, 1.0)] {
            let mut s = Series::default();
            s.push(0.0, before);
            for t in [0.01, 0.02, 0.03] {
                s.push(t, after);
            }
            assert_eq!(s.buckets.len(), 1);
            assert_eq!(
                s.points(),
                [(0.0, before), (0.01, after), (0.03, after)],
                "{before} to {after}"
            );
        }
    }

    /// One point a bucket (each in the middle of its 0.05 s, so that no rounding moves
    /// it): `BUCKETS` buckets fill, and the next point halves them (pairs merged, the width
    /// doubled to 0.1 s) before it takes a bucket of its own; never more than `BUCKETS`.
    #[test]
    fn buckets_merge_in_pairs_when_one_more_is_needed() {
        let mut s = Series::default();
        let at = |k: usize| k as f64 * 0.05 + 0.025;
        for k in 0..BUCKETS {
            s.push(at(k), k as f64);
        }
        assert_eq!(s.buckets.len(), BUCKETS);
        assert_eq!(s.width, 0.05);
        s.push(at(BUCKETS), 0.0);
        assert_eq!(s.buckets.len(), BUCKETS / 2 + 1);
        assert_eq!(s.width, 0.1);
        // Merged pairs: the first bucket now holds the first two points.
        assert_eq!(s.points()[..2], [(at(0), 0.0), (at(1), 1.0)]);
        // Each 0.1 s after that is a bucket of its own, up to the bound again.
        for k in 1..BUCKETS / 2 {
            s.push(at(BUCKETS) + k as f64 * 0.1, 0.0);
            assert!(s.buckets.len() <= BUCKETS);
        }
        assert_eq!(s.buckets.len(), BUCKETS);
        assert_eq!(s.width, 0.1);
    }

    /// Merging keeps each pair's extremes wherever they lie in their buckets, and of two
    /// equal ones the first.
    #[test]
    fn merged_buckets_keep_the_extremes_of_both() {
        let mut s = Series::default();
        // Bucket k: 5 at 0.01 s into it, its middle value at 0.025 s, 5 at 0.04 s.
        let at = |k: usize, into: f64| k as f64 * 0.05 + into;
        let middles = [0.0, 0.0, 10.0, 10.0, 0.0, -1.0, 10.0, 11.0];
        for k in 0..BUCKETS {
            let middle = middles.get(k).copied().unwrap_or(5.0);
            for (into, v) in [(0.01, 5.0), (0.025, middle), (0.04, 5.0)] {
                s.push(at(k, into), v);
            }
        }
        s.push(at(BUCKETS, 0.01), 5.0);
        let (start, middle, end) = (
            |k| (at(k, 0.01), 5.0),
            |k| at(k, 0.025),
            |k| (at(k, 0.04), 5.0),
        );
        assert_eq!(
            s.points()[..12],
            [
                // 0 and 0: the first 0.
                start(0),
                (middle(0), 0.0),
                end(1),
                // 10 and 10: the first 10.
                start(2),
                (middle(2), 10.0),
                end(3),
                // 0 and -1: the -1.
                start(4),
                (middle(5), -1.0),
                end(5),
                // 10 and 11: the 11.
                start(6),
                (middle(7), 11.0),
                end(7),
            ]
        );
    }

    /// A step at one instant (two points at one time) is drawn in the order it came, in
    /// either direction, each point once.
    #[test]
    fn a_step_at_one_instant_is_drawn_in_the_order_it_came() {
        for (a, b) in [(5.0, 0.0), (0.0, 5.0)] {
            let mut s = Series::default();
            for (t, v) in [(1.0, 2.0), (1.01, a), (1.01, b), (1.03, 2.0)] {
                s.push(t, v);
            }
            assert_eq!(
                s.points(),
                [(1.0, 2.0), (1.01, a), (1.01, b), (1.03, 2.0)],
                "{a} to {b}"
            );
        }
    }
}
